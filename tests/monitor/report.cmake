# The monitor's decoding and reports (docs/monitor.md "Reports"): a mon_t filled by hand, the
# exact lines, JSON (parsed with cJSON) and JUnit verdicts.
find_package(PkgConfig REQUIRED)
pkg_check_modules(MON_CJSON REQUIRED IMPORTED_TARGET libcjson)

# The core's accessors, until the core (src/monitor.c) is in the tree.
set(mon_report_stub "")
if(NOT EXISTS ${PROJECT_SOURCE_DIR}/sim_host/monitor/src/monitor.c)
  set(mon_report_stub ${CMAKE_CURRENT_LIST_DIR}/mon_core_stub.c)
endif()

add_executable(test_mon_decode ${CMAKE_CURRENT_LIST_DIR}/test_mon_decode.c ${mon_report_stub})
target_link_libraries(test_mon_decode PRIVATE dfp_monitor dfp_test_support)
target_compile_options(test_mon_decode PRIVATE ${DFP_WARNINGS})
add_test(NAME unit_mon_decode COMMAND test_mon_decode)

add_executable(test_mon_report ${CMAKE_CURRENT_LIST_DIR}/test_mon_report.c ${mon_report_stub})
target_link_libraries(test_mon_report PRIVATE dfp_monitor dfp_test_support PkgConfig::MON_CJSON)
target_compile_options(test_mon_report PRIVATE ${DFP_WARNINGS})
add_test(NAME unit_mon_report COMMAND test_mon_report)
