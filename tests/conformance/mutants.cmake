# Mutant cards (issue 33, "It must find defects"): the card with one of its rules broken at compile
# time, run through the whole conformance suite in process; the case named for the defect must
# FAIL and every other case PASS or be NOT APPLICABLE, as for the real card.
#
# No test hook in the protocol core: each mutant copies one source file of a card library into
# the build tree with one textual replacement and compiles it, with the library's other sources,
# into the mutant's program, ahead of the real libraries. GNU ld takes a symbol from the object
# files it is given and pulls an archive member only for a symbol still undefined; since every
# source of the replaced library is given, none of its members is pulled (a member pulled as
# well would stop the link with "multiple definition"). A replacement whose old text is not found
# exactly once stops the configuration: a mutation that no longer applies is never silently a
# copy of the real card.

# dfp_conformance_mutant(NAME LIBRARY FILE OLD NEW EXPECT...)
#   NAME     the mutant's name (test conformance_mutant_NAME)
#   LIBRARY  the card library the file belongs to (dfp_dp_slave, dfp_dpv1, dfp_dfp21b)
#   FILE     the source, relative to the library's source directory ("src/dp_slave.c")
#   OLD NEW  the replacement (bracket arguments: C text as it stands, semicolons and all)
#   EXPECT   the case ids that must fail; none for the real card
function(dfp_conformance_mutant name library file old new)
  set(expect ${ARGN})
  get_target_property(lib_dir ${library} SOURCE_DIR)
  get_target_property(lib_sources ${library} SOURCES)
  set(dir ${CMAKE_CURRENT_BINARY_DIR}/mutants/${name})
  set(sources "")
  if(NOT "${file}" STREQUAL "")
    set(original ${lib_dir}/${file})
    if(NOT "${file}" IN_LIST lib_sources)
      message(FATAL_ERROR "mutant ${name}: ${file} is not a source of ${library}")
    endif()
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${original})
    file(READ ${original} text)
    string(LENGTH "${text}" len_before)
    string(LENGTH "${old}" len_old)
    string(REPLACE "${old}" "" stripped "${text}")
    string(LENGTH "${stripped}" len_after)
    math(EXPR found "(${len_before} - ${len_after}) / ${len_old}")
    if(NOT found EQUAL 1)
      message(FATAL_ERROR "mutant ${name}: the text to replace occurs ${found} times in "
                          "${original}, not once:\n${old}")
    endif()
    string(REPLACE "${old}" "${new}" mutated "${text}")
    get_filename_component(base ${file} NAME)
    # written only when it changed, so a new configuration does not rebuild every mutant
    file(WRITE ${dir}/${base}.new "/* mutant ${name} of ${original} */\n${mutated}")
    configure_file(${dir}/${base}.new ${dir}/${base} COPYONLY)
    list(APPEND sources ${dir}/${base})
  endif()
  foreach(src ${lib_sources})
    if(NOT "${src}" STREQUAL "${file}")
      list(APPEND sources ${lib_dir}/${src})
    endif()
  endforeach()
  # The card's sources compile (and a mutation is checked) whether or not the suite's in-process
  # link is there to run them.
  set(card cf_mutant_${name}_card)
  add_library(${card} OBJECT ${sources})
  # the library's own definitions and its directory for its private headers
  target_include_directories(${card} PRIVATE ${lib_dir}/src)
  target_compile_definitions(${card} PRIVATE $<TARGET_PROPERTY:${library},COMPILE_DEFINITIONS>)
  target_compile_options(${card} PRIVATE ${DFP_WARNINGS})
  target_link_libraries(${card} PRIVATE ${library})
  if(NOT EXISTS ${PROJECT_SOURCE_DIR}/sim_host/conformance/include/conformance/cf_rig.h)
    return()
  endif()
  set(exe cf_mutant_${name})
  add_executable(${exe} ${CMAKE_CURRENT_LIST_DIR}/cf_mutant_main.c $<TARGET_OBJECTS:${card}>)
  target_compile_options(${exe} PRIVATE ${DFP_WARNINGS})
  target_link_libraries(${exe} PRIVATE dfp_conformance dfp_dfp21b ${library})
  list(JOIN expect "," expect_arg)
  add_test(NAME conformance_mutant_${name}
           COMMAND ${exe} ${PROJECT_SOURCE_DIR}/firmware/gsd/SEWA6003.GSD "${expect_arg}")
  set_tests_properties(conformance_mutant_${name} PROPERTIES TIMEOUT 120)
endfunction()

if(NOT TARGET dfp_dfp21b)
  return()
endif()

# The real card through the same machinery: no case fails.
dfp_conformance_mutant(none dfp_dp_slave "" "" "")

# Data_Exchange in Wait_Cfg is carried out instead of refused.
dfp_conformance_mutant(wait_cfg_data_exchange dfp_dp_slave src/dp_services.c
  [[[DDLM_DATA_EXCHANGE] = {"DDLM_Data_Exchange", "Data_Exchange", false, DP_LOCK_OWNER_OR_RS,
                            {RS, RS, X}},]]
  [[[DDLM_DATA_EXCHANGE] = {"DDLM_Data_Exchange", "Data_Exchange", false, DP_LOCK_OWNER_OR_RS,
                            {RS, X, X}},]]
  dp.wait_cfg.data_exchange)

# Set_Prm from any master is carried out while another one holds the lock.
dfp_conformance_mutant(set_prm_ignores_lock dfp_dp_slave src/dp_services.c
  [[[DDLM_SET_PRM] = {"DDLM_Set_Prm", "Set_Prm", false, DP_LOCK_OWNER_OR_RS, {X, X, X}},]]
  [[[DDLM_SET_PRM] = {"DDLM_Set_Prm", "Set_Prm", false, DP_LOCK_ANY, {X, X, X}},]]
  dp.set_prm.lock)

# A second locking Set_Prm in Wait_Cfg drops the slave back to Wait_Prm without a Prm_Fault,
# still locked: Chk_Cfg is then only acknowledged and Data_Exch never comes (the VPC3+ defect
# "two Set_Prm in a row hang the stack"); an unlock releases it.
dfp_conformance_mutant(set_prm_repeated_hangs dfp_dp_slave src/dp_slave.c
  [[    adopt_prm(s, m, dpv1, t);
}]]
  [[    if (s->state == DP_STATE_WAIT_CFG) {
        set_state(s, DP_STATE_WAIT_PRM, t);
        s->master_add = m->sa;
        return;
    }
    adopt_prm(s, m, dpv1, t);
}]]
  dp.set_prm.repeated)

# WD_On (Station_status_2 bit 3) is never shown, though the watchdog runs.
dfp_conformance_mutant(diag_no_wd_on dfp_dp_slave src/dp_slave.c
  [[        st2 |= DP_DIAG2_WD_ON;]]
  [[        st2 |= 0u;]]
  dp.diag.data_exch)

# Answers go out at the end of the request, whatever min TSDR Set_Prm asked for.
dfp_conformance_mutant(tsdr_below_min dfp_dp_slave src/fdl_station.c
  [[    hal_time_us_t not_before = request_end + s->min_tsdr_us;]]
  [[    hal_time_us_t not_before = request_end;]]
  timing.tsdr.min)

# The DP watchdog is armed and shown (WD_On) but never expires.
dfp_conformance_mutant(watchdog_never_expires dfp_dp_slave src/dp_slave.c
  [[    if (s->wd_on && s->state != DP_STATE_WAIT_PRM) {]]
  [[    if (s->wd_on && s->state != DP_STATE_WAIT_PRM && s->wd_time_us == 0u) {]]
  dp.watchdog.expiry)

# A third MSAC2 Initiate takes over the first connection instead of being refused.
dfp_conformance_mutant(msac2_third_accepted dfp_dpv1 src/dpv1.c
  [[    if (free_slot < 0) {
        d->c2_refused++;
        return abort_reply(DPV1_ABORT_REASON_RESOURCE, reply);
    }]]
  [[    if (free_slot < 0) {
        free_slot = 0;
    }]]
  dpv1.msac2.third_refused)

# The FCB is never remembered: a repetition is carried out again.
dfp_conformance_mutant(fcb_ignored dfp_dp_slave src/fdl_station.c
  [[    slot->fcb_valid = fcv || fcb != 0u;]]
  [[    slot->fcb_valid = false;]]
  fdl.fcb_repeat)

# Requests to any destination address are served as the slave's own.
dfp_conformance_mutant(answers_other_address dfp_dp_slave src/fdl_station.c
  [[    if (m->da != s->cfg.address && !broadcast) {
        return false;
    }]]
  [[    (void)broadcast;]]
  fdl.other_address)
