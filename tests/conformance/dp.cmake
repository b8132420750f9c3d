# The DP state machine group (sim_host/conformance/src/cases_dp*.c) against the card in process
# at every rate with both GSD files and against dfp-sim slave on a PTY.
add_test(NAME conformance_dp
         COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test_cases_dp.sh $<TARGET_FILE:dfp-sim>
                 ${PROJECT_SOURCE_DIR}/firmware/gsd)
set_tests_properties(conformance_dp PROPERTIES TIMEOUT 120)
