# The conformance reports (sim_host/conformance/include/conformance/cf_report.h): results built
# by hand, the terminal's exact lines, JUnit and HTML read back by Python's XML and HTML parsers.
if(NOT DFP_PYTHON)
  find_package(Python3 COMPONENTS Interpreter)
  set(cf_report_python "${Python3_EXECUTABLE}")
else()
  set(cf_report_python "${DFP_PYTHON}")
endif()
add_executable(test_cf_report ${CMAKE_CURRENT_LIST_DIR}/test_cf_report.c)
target_link_libraries(test_cf_report PRIVATE dfp_conformance dfp_test_support)
target_compile_options(test_cf_report PRIVATE ${DFP_WARNINGS})
target_compile_definitions(test_cf_report PRIVATE _GNU_SOURCE)
add_test(NAME unit_cf_report
         COMMAND test_cf_report ${cf_report_python} ${CMAKE_CURRENT_LIST_DIR}/cf_report_parse.py
         WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
