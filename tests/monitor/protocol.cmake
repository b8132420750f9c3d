# The monitor's reading of the DP slave state machine against dp_slave.c, telegram by telegram
# (Lock_Req/Unlock_Req, min TSDR, Stat_Diag in data exchange).
add_executable(test_mon_protocol ${CMAKE_CURRENT_LIST_DIR}/test_mon_protocol.c)
target_link_libraries(test_mon_protocol PRIVATE dfp_monitor dfp_test_support)
target_compile_options(test_mon_protocol PRIVATE ${DFP_WARNINGS})
add_test(NAME unit_mon_protocol COMMAND test_mon_protocol)
target_compile_definitions(test_mon_protocol PRIVATE _GNU_SOURCE) # mkstemp, fdopen
