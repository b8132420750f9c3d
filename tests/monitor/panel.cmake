# The monitor for the control API and the panel's bus page: rig_doc, mon_rig on the in-memory
# bus and the route GET /api/v1/bus (test_mon_bus_doc.c); the route's access rules, its document
# and the "bus" log events against `dfp-sim demo --http` (test_bus_api.sh). The page itself is
# checked in tests/panel (panel_browser).
add_executable(test_mon_bus_doc ${CMAKE_CURRENT_LIST_DIR}/test_mon_bus_doc.c)
target_link_libraries(test_mon_bus_doc PRIVATE dfp_monitor dfp_rig dfp_http dfp_test_support)
target_compile_options(test_mon_bus_doc PRIVATE ${DFP_WARNINGS})
target_compile_definitions(test_mon_bus_doc PRIVATE _GNU_SOURCE)
add_test(NAME monitor_rig COMMAND test_mon_bus_doc)
set_tests_properties(monitor_rig PROPERTIES TIMEOUT 60)

if(TARGET dfp-sim)
  add_test(NAME monitor_bus_api
           COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_bus_api.sh $<TARGET_FILE:dfp-sim>)
  set_tests_properties(monitor_bus_api PROPERTIES TIMEOUT 120)
endif()
