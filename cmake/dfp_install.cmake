# What the host build installs beside dfp-sim (whose own rules, with its man page and shell
# completions, are in sim_host/dfp_sim/CMakeLists.txt), and the Debian package of it all
# (`make install`, `make package`: mk/install.mk). Paths are relative to the install prefix, so
# one configuration serves `cmake --install --prefix DIR` and the .deb (prefix /usr) alike.
include(GNUInstallDirs)

file(GLOB _dfp_gsd CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/firmware/gsd/*.GSD")
install(FILES ${_dfp_gsd} DESTINATION "${CMAKE_INSTALL_DATADIR}/dfp21b/gsd")

# Debian's Wireshark loads every .lua file below its global Lua plugin folder
# (`tshark -G folders`: /usr/lib/<multiarch>/wireshark/plugins), subfolders included; the
# dissector's parts stay together in a folder of their own (tools/wireshark/README.md).
if(CMAKE_LIBRARY_ARCHITECTURE)
  set(_dfp_ws_default "lib/${CMAKE_LIBRARY_ARCHITECTURE}/wireshark/plugins")
else()
  set(_dfp_ws_default "${CMAKE_INSTALL_LIBDIR}/wireshark/plugins")
endif()
set(DFP_WIRESHARK_LUA_DIR "${_dfp_ws_default}" CACHE STRING
    "Wireshark's global Lua plugin folder, relative to the install prefix")
file(GLOB _dfp_lua CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/tools/wireshark/*.lua")
install(FILES ${_dfp_lua} DESTINATION "${DFP_WIRESHARK_LUA_DIR}/dfp21b")

# The Python client where Debian puts pure-Python modules of its python3-* packages: on the
# path of Debian's python3 without PYTHONPATH, for every python3 version.
set(DFP_PYTHON_INSTALL_DIR "lib/python3/dist-packages" CACHE STRING
    "Where the dfpsim Python package goes, relative to the install prefix")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/python/dfpsim" DESTINATION "${DFP_PYTHON_INSTALL_DIR}"
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)

# The .deb: make package (cpack in the build directory). Its shared-library dependencies come
# from the binary through dpkg-shlibdeps (dpkg-dev); without it, the list ldd shows today.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME dfp21b-sim)
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGE_CONTACT "DFP21B open firmware")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION electronics)
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "the SEW DFP21B PROFIBUS-DP card, simulated on Linux")
# The summary is the Description's first line; CPack indents these below it.
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "dfp-sim: the emulated DFP21B PROFIBUS-DP option card with an
emulated MOVIDRIVE behind it, on a tty, a PTY or a virtual segment over LCM, and a class-1 DP
master, parameter services, captures, replay and record. With its man page, bash and zsh
completions, the card's GSD files, a Wireshark dissector for PROFIBUS and the dfpsim Python
client.")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3 (>= 3.11), socat, tshark | wireshark")
find_program(DFP_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(DFP_DPKG_SHLIBDEPS)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  set(CPACK_DEBIAN_PACKAGE_DEPENDS "libc6, libglib2.0-0, libmicrohttpd12, libcjson1, libpcap0.8")
endif()
include(CPack)
