# The Timing and DP-V1 groups against the card in process (every rate) and dfp-sim slave on a PTY.
add_test(NAME conformance_v1t
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/test_v1t.sh $<TARGET_FILE:dfp-sim> ${PROJECT_SOURCE_DIR})
