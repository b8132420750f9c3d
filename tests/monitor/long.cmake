# dfp-sim monitor over a long run: --seconds past the 32-bit microsecond clock's wrap
# (test_monitor_long.sh), on a clock that runs 4096 times as fast (clock_fast.c, preloaded).
if(TARGET dfp-sim)
  add_library(mon_clock_fast MODULE ${CMAKE_CURRENT_LIST_DIR}/clock_fast.c)
  target_compile_options(mon_clock_fast PRIVATE ${DFP_WARNINGS} -fno-lto)
  target_link_libraries(mon_clock_fast PRIVATE ${CMAKE_DL_LIBS})
  add_test(NAME cli_monitor_long
           COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_monitor_long.sh $<TARGET_FILE:dfp-sim>
                   $<TARGET_FILE:mon_clock_fast>)
  set_tests_properties(cli_monitor_long PROPERTIES TIMEOUT 60)
endif()
