# The monitor's terminal view: the renderer's exact lines, the keys and the escape-sequence
# decoder (unit_mon_view), and the terminal on a real PTY pair (unit_mon_view_term).
add_executable(test_mon_view ${CMAKE_CURRENT_LIST_DIR}/test_mon_view.c)
target_link_libraries(test_mon_view PRIVATE dfp_monitor dfp_test_support)
target_compile_options(test_mon_view PRIVATE ${DFP_WARNINGS})
target_compile_definitions(test_mon_view PRIVATE _GNU_SOURCE) # openpty
add_test(NAME unit_mon_view COMMAND test_mon_view view)
add_test(NAME unit_mon_view_term COMMAND test_mon_view term)
set_tests_properties(unit_mon_view unit_mon_view_term PROPERTIES TIMEOUT 60)
