# The whole suite against the card in process (every rate, both GSD files) and dfp-sim slave on a
# PTY and on a port of the virtual line, the reports, and bad command lines.
add_test(NAME conformance_suite
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_suite.sh $<TARGET_FILE:dfp-sim> ${PROJECT_SOURCE_DIR})
set_tests_properties(conformance_suite PROPERTIES TIMEOUT 600)
# The suite against dfp-sim slave on an LCM segment, in a private network namespace for udpm
# (tests/lcm/netns.sh): exit 77 (skipped) where none can be made.
add_test(NAME conformance_suite_lcm
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_suite_lcm.sh $<TARGET_FILE:dfp-sim> ${PROJECT_SOURCE_DIR})
set_tests_properties(conformance_suite_lcm PROPERTIES TIMEOUT 300 SKIP_RETURN_CODE 77)
# A slave answering after the tester's slot time, behind a relay (late_relay.py): late answers
# taken for the retry of the same request and the rest settled, never shifted onto the next.
add_test(NAME conformance_late_slave
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_late_slave.sh $<TARGET_FILE:dfp-sim> ${PROJECT_SOURCE_DIR})
set_tests_properties(conformance_late_slave PROPERTIES TIMEOUT 300)
