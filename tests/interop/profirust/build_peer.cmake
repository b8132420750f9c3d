# cmake -DCARGO=... -DMANIFEST=.../Cargo.toml -DTARGET_DIR=... -DREQUIRED=ON|OFF -P build_peer.cmake
# Builds dfp-profirust-peer with Cargo.lock as it is (--locked): from the crates already in
# ~/.cargo first (no network), else with a download bounded in time. A build that fails says why
# in one block; it stops the build only when the interop tests are required (DFP_REQUIRE_INTEROP),
# otherwise the peer's tests skip and name this message.
set(env CARGO_TARGET_DIR=${TARGET_DIR} CARGO_TERM_COLOR=never
        CARGO_HTTP_TIMEOUT=30 CARGO_NET_RETRY=2 CARGO_HTTP_LOW_SPEED_LIMIT=1)
set(build ${CARGO} build --release --locked --manifest-path ${MANIFEST})
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${env} ${build} --offline --quiet
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE offline_err)
if(rc EQUAL 0)
  return()
endif()
message(STATUS "dfp-profirust-peer: crates not all in ~/.cargo yet, fetching them (at most 10 min)")
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${env} ${build}
                RESULT_VARIABLE rc ERROR_VARIABLE err TIMEOUT 600)
if(rc EQUAL 0)
  return()
endif()
file(REMOVE ${TARGET_DIR}/release/dfp-profirust-peer)
string(REGEX REPLACE "\n$" "" err "${err}")
set(msg "dfp-profirust-peer: cargo could not build it (${rc}); the crates.io download fails \
when the machine is offline or crates.io is unreachable, and then the profirust interop tests \
cannot run. cargo said:\n${err}")
if(REQUIRED)
  message(FATAL_ERROR "${msg}")
else()
  message(WARNING "${msg}\nThe profirust interop tests will skip (DFP_REQUIRE_INTEROP is OFF).")
endif()
