# The helpers of the conformance suite's GSD and FDL groups (cf_cases_fdl.h) that need no slave.
if(TARGET dfp_conformance)
  add_executable(test_cases_fdl ${CMAKE_CURRENT_LIST_DIR}/test_cases_fdl.c)
  target_link_libraries(test_cases_fdl PRIVATE dfp_conformance dfp_test_support)
  target_compile_options(test_cases_fdl PRIVATE ${DFP_WARNINGS})
  add_test(NAME unit_cases_fdl COMMAND test_cases_fdl)
endif()
