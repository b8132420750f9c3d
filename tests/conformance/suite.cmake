# The whole suite against the card in process (every rate, both GSD files) and dfp-sim slave on a
# PTY, the reports, and bad command lines.
add_test(NAME conformance_suite
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_suite.sh $<TARGET_FILE:dfp-sim> ${PROJECT_SOURCE_DIR})
set_tests_properties(conformance_suite PROPERTIES TIMEOUT 600)
