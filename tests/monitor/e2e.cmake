# dfp-sim monitor as a person uses it, end to end: the full-screen view on a PTY against a port
# of dfp-sim line (monitor_top), the panel's bus page in headless chromium against the monitor's
# --http (monitor_panel_browser), and the monitor on an LCM segment, plain and keyed
# (monitor_lcm).
if(NOT TARGET dfp-sim)
  return()
endif()
if(DFP_PYTHON)
  set(mon_e2e_python "${DFP_PYTHON}")
else()
  find_package(Python3 COMPONENTS Interpreter)
  set(mon_e2e_python "${Python3_EXECUTABLE}")
endif()

add_test(NAME monitor_top
         COMMAND ${mon_e2e_python} -B ${CMAKE_CURRENT_LIST_DIR}/test_monitor_top.py
                 $<TARGET_FILE:dfp-sim>)
set_tests_properties(monitor_top PROPERTIES TIMEOUT 120)

# A private network namespace for udpm (tests/lcm/netns.sh): exit 77 where none can be made.
add_test(NAME monitor_lcm
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_monitor_lcm.sh $<TARGET_FILE:dfp-sim>
                 ${mon_e2e_python})
set_tests_properties(monitor_lcm PROPERTIES TIMEOUT 120 SKIP_RETURN_CODE 77)

# chromium and selenium (DFP_PYTHON's): skipped (77) where they are missing, unless
# DFP_REQUIRE_INTEROP, as panel_browser (tests/panel/, whose conftest.py finds the tools).
if(DFP_PYTHON)
  set(mon_e2e_require "")
  if(DFP_REQUIRE_INTEROP)
    set(mon_e2e_require --require-tools)
  endif()
  add_test(NAME monitor_panel_browser
           COMMAND ${DFP_PYTHON} -B ${CMAKE_CURRENT_LIST_DIR}/test_monitor_panel.py
                   $<TARGET_FILE:dfp-sim> ${mon_e2e_require})
  # chromium and wall-clock start-ups: keep the other tests off the cores
  set_tests_properties(monitor_panel_browser PROPERTIES TIMEOUT 180 RUN_SERIAL TRUE)
  if(NOT DFP_REQUIRE_INTEROP)
    set_tests_properties(monitor_panel_browser PROPERTIES SKIP_RETURN_CODE 77)
  endif()
endif()
