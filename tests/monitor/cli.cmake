# dfp-sim monitor end to end (test_monitor_cli.sh): offline, its pcapng, live on the line, and
# bad command lines.
if(TARGET dfp-sim)
  if(NOT DFP_PYTHON)
    find_package(Python3 COMPONENTS Interpreter)
    set(monitor_python "${Python3_EXECUTABLE}")
  else()
    set(monitor_python "${DFP_PYTHON}")
  endif()
  add_test(NAME cli_monitor COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_monitor_cli.sh
                                    $<TARGET_FILE:dfp-sim> ${monitor_python})
  set_tests_properties(cli_monitor PROPERTIES TIMEOUT 120)
endif()
