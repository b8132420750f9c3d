# dfp-sim monitor --view top on a PTY: the keys that end it give the terminal back
# (test_monitor_tty.py).
if(TARGET dfp-sim)
  if(NOT DFP_PYTHON)
    find_package(Python3 COMPONENTS Interpreter)
    set(monitor_tty_python "${Python3_EXECUTABLE}")
  else()
    set(monitor_tty_python "${DFP_PYTHON}")
  endif()
  add_test(NAME cli_monitor_tty
           COMMAND ${monitor_tty_python} ${CMAKE_CURRENT_LIST_DIR}/test_monitor_tty.py
                   $<TARGET_FILE:dfp-sim>)
  set_tests_properties(cli_monitor_tty PROPERTIES TIMEOUT 60)
endif()
