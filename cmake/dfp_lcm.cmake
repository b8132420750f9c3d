# LCM 1.5 for the host build and the fuzz build: lcm-gen, the static liblcm and its headers from
# the `lcm` wheel (PyPI) that `make` installs into the project's venv. Debian ships 1.3.1, whose
# UDP fragment reassembly trusts a fragment's offset: two datagrams from anyone who can reach the
# multicast group crash every subscriber (sim_host/lcm_bridge/README.md, "Who can reach a segment").
# Linked statically, so dfp-sim runs without the venv (only glib, which liblcm needs, is shared).
#
# Sets LCM_GEN, LCM_INCLUDE_DIR, LCM_VERSION and the imported target dfp::lcm.
set(DFP_LCM_MIN_VERSION 1.5.0)
set(DFP_LCM_PREFIX "" CACHE PATH
    "Where LCM >= ${DFP_LCM_MIN_VERSION} is (bin/lcm-gen, lib/liblcm.a, include/lcm); default: the lcm wheel in build/venv")
if(NOT DFP_LCM_PREFIX)
  get_filename_component(_dfp_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
  file(GLOB _dfp_lcm_candidates "${_dfp_root}/build/venv/lib/python3*/site-packages")
  if(_dfp_lcm_candidates)
    list(GET _dfp_lcm_candidates 0 _dfp_lcm_prefix)
    set(DFP_LCM_PREFIX "${_dfp_lcm_prefix}" CACHE PATH "" FORCE)
  endif()
endif()

find_program(DFP_LCM_GEN lcm-gen HINTS "${DFP_LCM_PREFIX}/bin" NO_DEFAULT_PATH)
find_library(DFP_LCM_STATIC_LIBRARY NAMES liblcm.a HINTS "${DFP_LCM_PREFIX}/lib" NO_DEFAULT_PATH)
find_path(DFP_LCM_INCLUDE_DIR lcm/lcm_version.h HINTS "${DFP_LCM_PREFIX}/include" NO_DEFAULT_PATH)
find_library(GLIB_LIBRARY glib-2.0)
if(NOT DFP_LCM_GEN OR NOT DFP_LCM_STATIC_LIBRARY OR NOT DFP_LCM_INCLUDE_DIR OR NOT GLIB_LIBRARY)
  message(FATAL_ERROR "LCM >= ${DFP_LCM_MIN_VERSION} not found in '${DFP_LCM_PREFIX}' "
                      "(lcm-gen: ${DFP_LCM_GEN}, liblcm.a: ${DFP_LCM_STATIC_LIBRARY}, headers: "
                      "${DFP_LCM_INCLUDE_DIR}, glib-2.0: ${GLIB_LIBRARY}). `make deps` installs the "
                      "lcm wheel into build/venv; or give -DDFP_LCM_PREFIX=DIR.")
endif()
# Cache names of their own: a build directory configured before kept Debian's in LCM_*.
set(LCM_GEN "${DFP_LCM_GEN}")
set(LCM_STATIC_LIBRARY "${DFP_LCM_STATIC_LIBRARY}")
set(LCM_INCLUDE_DIR "${DFP_LCM_INCLUDE_DIR}")

file(STRINGS "${LCM_INCLUDE_DIR}/lcm/lcm_version.h" _dfp_lcm_v
     REGEX "#define LCM_VERSION_(MAJOR|MINOR|PATCH) [0-9]+")
string(REGEX REPLACE ".*MAJOR ([0-9]+).*MINOR ([0-9]+).*PATCH ([0-9]+).*" "\\1.\\2.\\3"
       LCM_VERSION "${_dfp_lcm_v}")
if(LCM_VERSION VERSION_LESS DFP_LCM_MIN_VERSION)
  message(FATAL_ERROR "LCM ${LCM_VERSION} in ${DFP_LCM_PREFIX} is older than "
                      "${DFP_LCM_MIN_VERSION}: its fragment reassembly can be crashed from the net")
endif()

if(NOT TARGET dfp::lcm)
  add_library(dfp::lcm STATIC IMPORTED GLOBAL)
  set_target_properties(dfp::lcm PROPERTIES
    IMPORTED_LOCATION "${LCM_STATIC_LIBRARY}"
    INTERFACE_LINK_LIBRARIES "${GLIB_LIBRARY};pthread")
  # SYSTEM: lcm.h is not ours to keep free of warnings.
  set_property(TARGET dfp::lcm PROPERTY INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
  set_property(TARGET dfp::lcm PROPERTY INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
endif()
message(STATUS "LCM ${LCM_VERSION}: ${LCM_STATIC_LIBRARY}")
