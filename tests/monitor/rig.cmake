# The monitor on the in-memory bus (rings of masters with DFP21B cards, the rig's faults), and
# the character receiver on damaged and random streams.
add_library(dfp_ring_mon STATIC ${CMAKE_CURRENT_SOURCE_DIR}/ring_mon.c)
target_include_directories(dfp_ring_mon PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(dfp_ring_mon PUBLIC dfp_ring_rig dfp_monitor)
target_compile_options(dfp_ring_mon PRIVATE ${DFP_WARNINGS})
foreach(t mon_rig mon_rig_ring)
  add_executable(test_${t} ${CMAKE_CURRENT_SOURCE_DIR}/test_${t}.c)
  target_link_libraries(test_${t} PRIVATE dfp_ring_mon)
  target_compile_options(test_${t} PRIVATE ${DFP_WARNINGS})
endforeach()
add_test(NAME unit_mon_rig COMMAND test_mon_rig)
add_test(NAME unit_mon_rig_ring COMMAND test_mon_rig_ring)
add_executable(test_mon_rig_frames ${CMAKE_CURRENT_SOURCE_DIR}/test_mon_rig_frames.c)
target_link_libraries(test_mon_rig_frames PRIVATE dfp_monitor dfp_test_support)
target_compile_options(test_mon_rig_frames PRIVATE ${DFP_WARNINGS})
add_test(NAME unit_mon_rig_frames COMMAND test_mon_rig_frames)
# The receiver with mon_telegram wrapped, so the test sees each telegram it hands on: --wrap
# only reaches calls between ordinary objects, so the monitor's sources are built into the test
# without link-time optimisation instead of taken from dfp_monitor.
set(mon_chars_core)
foreach(src monitor.c mon_dp.c mon_chars.c mon_sink.c)
  list(APPEND mon_chars_core ${CMAKE_SOURCE_DIR}/sim_host/monitor/src/${src})
endforeach()
add_executable(test_mon_chars ${CMAKE_CURRENT_SOURCE_DIR}/test_mon_chars.c ${mon_chars_core})
target_include_directories(test_mon_chars PRIVATE ${CMAKE_SOURCE_DIR}/sim_host/monitor/include)
target_link_libraries(test_mon_chars PRIVATE dfp_dp_slave dfp_fdl_active dfp_replay
                      dfp_test_support -Wl,--wrap=mon_telegram)
target_compile_options(test_mon_chars PRIVATE ${DFP_WARNINGS} -fno-lto)
add_test(NAME unit_mon_chars COMMAND test_mon_chars)
