/* rig_ctl's command slots: what a client that stops waiting leaves behind. A line of two cards
 * (addresses 4 and 5, emulated drives) on the in-memory bus; the bus loop is either absent (a
 * stalled loop: a replay waiting for input, a stopped process) or a thread that calls
 * rig_ctl_service as the real loop does. Also: a command to an address two cards share. */
#include <pthread.h>
#include <stdio.h>
#include <stdatomic.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "rig/rig.h"
#include "rig/rig_ctl.h"

static rig_t rig;
static rig_ctl_t ctl;

static void setup(void)
{
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .baud = 1500000u};
    rig_init(&rig, &rc);
    char err[128];
    CHECK_EQ(rig_open(&rig, err, sizeof err), 0);
    for (uint8_t a = 4; a <= 5; a++) {
        card_options_t co = {.address = a, .inverter = CARD_INVERTER_SIM};
        CHECK(rig_add_card(&rig, &co, membus_now_us(&rig.bus)) != NULL);
    }
    CHECK_EQ(rig_ctl_init(&ctl, &rig, "slave", false), 0);
}

static void teardown(void)
{
    rig_ctl_destroy(&ctl);
    rig_close(&rig);
}

static unsigned free_slots(void)
{
    unsigned n = 0;
    for (unsigned i = 0; i < RIG_CTL_CMDS; i++) {
        n += atomic_load(&ctl.slot[i]) == RIG_SLOT_FREE ? 1u : 0u;
    }
    return n;
}

/* ---- the bus loop as a thread -------------------------------------------------------------- */

static atomic_bool loop_stop;

static void *loop_main(void *arg)
{
    (void)arg;
    const struct timespec ms = {0, 1000000L};
    while (!atomic_load(&loop_stop)) {
        rig_ctl_service(&ctl, 1000000000u);
        nanosleep(&ms, NULL);
    }
    return NULL;
}

/* Runs cmd with the loop turning; the loop is stopped again before it returns, so the caller
 * may look at the rig. */
static void submit_with_loop(rig_cmd_t *cmd)
{
    pthread_t t;
    atomic_store(&loop_stop, false);
    CHECK_EQ(pthread_create(&t, NULL, loop_main, NULL), 0);
    (void)rig_ctl_submit(&ctl, cmd, 2000u);
    atomic_store(&loop_stop, true);
    pthread_join(t, NULL);
}

/* ---- tests --------------------------------------------------------------------------------- */

/* More timed-out commands than there are slots, none of them taken up: each is withdrawn (504
 * saying so), no slot stays taken, and none is carried out later when the loop runs again. */
static void test_queued_timeout_is_withdrawn(void)
{
    setup();
    for (unsigned i = 0; i < RIG_CTL_CMDS + 4u; i++) {
        rig_cmd_t cmd = {.type = RIG_CMD_FAULT, .card = 4, .value = 11};
        CHECK(!rig_ctl_submit(&ctl, &cmd, 5u));
        CHECK_EQ(cmd.status, 504);
        CHECK_STR(cmd.error, "the simulation did not take the action up within 5 ms; it was "
                             "withdrawn and not carried out");
    }
    CHECK_EQ(free_slots(), RIG_CTL_CMDS);
    rig_ctl_service(&ctl, 0u);
    CHECK_EQ(rig.cards[0].cs.md.fault, 0);
    rig_cmd_t cmd = {.type = RIG_CMD_FAULT, .card = 4, .value = 14};
    submit_with_loop(&cmd);
    CHECK_EQ(cmd.status, 200);
    CHECK_EQ(rig.cards[0].cs.md.fault, 14);
    CHECK_EQ(free_slots(), RIG_CTL_CMDS);
    teardown();
}

/* The loop's side of a command it has taken up and not finished (a master parameter service):
 * the slot RUNNING, as rig_ctl_service leaves it. */
static void *take_up_first(void *arg)
{
    (void)arg;
    const struct timespec ms = {0, 1000000L};
    for (int seen = RIG_SLOT_QUEUED;
         !atomic_compare_exchange_strong(&ctl.slot[0], &seen, RIG_SLOT_RUNNING);
         seen = RIG_SLOT_QUEUED) {
        nanosleep(&ms, NULL);
    }
    return NULL;
}

/* A command the loop is running when its client gives up cannot be called back: the slot is
 * left to the loop (ABANDONED, freed when it ends) and the 504 says it may still happen. */
static void test_running_timeout_may_still_happen(void)
{
    setup();
    pthread_t t;
    CHECK_EQ(pthread_create(&t, NULL, take_up_first, NULL), 0);
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_PARAM, .card = 4, .index = 8461};
    CHECK(!rig_ctl_submit(&ctl, &cmd, 50u));
    pthread_join(t, NULL);
    CHECK_EQ(cmd.status, 504);
    CHECK_STR(cmd.error, "no answer within 50 ms; the action may still be carried out");
    CHECK_EQ(atomic_load(&ctl.slot[0]), RIG_SLOT_ABANDONED);
    CHECK_EQ(free_slots(), RIG_CTL_CMDS - 1u);
    teardown();
}

/* A DIP address another card answers to, now or after its power cycle, is refused: the line
 * never gets two cards at one address through the API. */
static void test_dip_to_a_used_address_is_refused(void)
{
    setup();
    rig_cmd_t dip = {.type = RIG_CMD_DIP, .card = 4, .value = 5};
    submit_with_loop(&dip);
    CHECK_EQ(dip.status, 409);
    CHECK_STR(dip.error, "card 2 of the line answers to address 5: two cards must not share an "
                         "address");
    CHECK_EQ(rig.cards[0].next_address, 4);
    rig_cmd_t nine = {.type = RIG_CMD_DIP, .card = 5, .value = 9};
    submit_with_loop(&nine);
    CHECK_EQ(nine.status, 200);
    rig_cmd_t also_nine = {.type = RIG_CMD_DIP, .card = 4, .value = 9};
    submit_with_loop(&also_nine);
    CHECK_EQ(also_nine.status, 409);
    CHECK_STR(also_nine.error, "card 2 of the line answers to address 9 after its power cycle: "
                               "two cards must not share an address");
    rig_cmd_t own = {.type = RIG_CMD_DIP, .card = 4, .value = 4};
    submit_with_loop(&own);
    CHECK_EQ(own.status, 200);
    teardown();
}

/* Two cards at address 5 all the same (switches set outside the API): a command to 5 reaches
 * neither (409), since either might be the one meant. */
static void test_ambiguous_address_is_refused(void)
{
    setup();
    rig_card_set_dip(&rig.cards[0], 5);
    rig_cmd_t cycle = {.type = RIG_CMD_POWER_CYCLE, .card = 4};
    submit_with_loop(&cycle);
    CHECK_EQ(cycle.status, 200);
    CHECK_EQ(rig.cards[0].cs.card.address, 5);
    rig_cmd_t fault = {.type = RIG_CMD_FAULT, .card = 5, .value = 11};
    submit_with_loop(&fault);
    CHECK_EQ(fault.status, 409);
    CHECK_STR(fault.error, "2 cards answer to address 5 (DIP switches); the API cannot tell "
                           "which one is meant");
    CHECK_EQ(rig.cards[0].cs.md.fault, 0);
    CHECK_EQ(rig.cards[1].cs.md.fault, 0);
    rig_cmd_t read = {.type = RIG_CMD_PARAM_READ, .card = 5, .index = 8470};
    submit_with_loop(&read);
    CHECK_EQ(read.status, 409);
    teardown();
}

/* A thread other than the loop in the middle of writing an event (it holds the writers' lock)
 * does not hold the loop up: the loop's events wait in its queue, in order, and reach the ring
 * at the next service turn; past the queue's room they are counted in one "lost" event. */
static void test_loop_never_waits_for_a_writer(void)
{
    setup();
    rig_ctl_event(&ctl, 1u, RIG_LOG_INFO, "sim", "test", "before");
    CHECK_EQ(pthread_mutex_lock(&ctl.ev_lock), 0);
    const unsigned n = RIG_CTL_STAGED + 44u;
    for (unsigned i = 0; i < n; i++) {
        char text[32];
        (void)snprintf(text, sizeof text, "staged %u", i);
        rig_ctl_event(&ctl, 2u + i, RIG_LOG_INFO, "sim", "test", text);
    }
    rig_ctl_service(&ctl, 0u);
    CHECK_EQ(rig_ctl_next_seq(&ctl), 1u);
    CHECK_EQ(pthread_mutex_unlock(&ctl.ev_lock), 0);
    rig_ctl_service(&ctl, 0u);
    CHECK_EQ(rig_ctl_next_seq(&ctl), 2u + RIG_CTL_STAGED);
    static rig_ctl_event_t ev[RIG_CTL_STAGED + 2u];
    uint64_t lost = 99;
    CHECK_EQ(rig_ctl_events(&ctl, 0u, ev, RIG_CTL_STAGED + 2u, &lost), RIG_CTL_STAGED + 2u);
    CHECK_EQ(lost, 0u);
    CHECK_STR(ev[0].text, "before");
    CHECK_STR(ev[1].text, "staged 0");
    CHECK_STR(ev[RIG_CTL_STAGED].text, "staged 255");
    CHECK_EQ(ev[RIG_CTL_STAGED].seq, RIG_CTL_STAGED);
    CHECK_STR(ev[RIG_CTL_STAGED + 1u].kind, "lost");
    CHECK_STR(ev[RIG_CTL_STAGED + 1u].text, "44 log events dropped while the log was busy");
    teardown();
}

/* ---- readers against a writer (run under ThreadSanitizer too) ------------------------------- */

static atomic_bool writer_done;
static atomic_uint torn;

static void *event_writer(void *arg)
{
    (void)arg;
    for (unsigned i = 0; i < 3u * RIG_CTL_EVENTS; i++) {
        uint64_t seq = rig_ctl_next_seq(&ctl);
        char text[32];
        (void)snprintf(text, sizeof text, "event %llu", (unsigned long long)seq);
        rig_ctl_event(&ctl, seq, RIG_LOG_INFO, "sim", "test", text);
        if (i % 64u == 0u) {
            rig_ctl_service(&ctl, 0u);
        }
    }
    atomic_store(&writer_done, true);
    return NULL;
}

/* Every event read is whole (its text names its own seq, its time is its seq), every snapshot
 * one publication (its cards' count is the rig's), and the seqs come in order without gaps
 * except those reported lost. */
static void *event_reader(void *arg)
{
    (void)arg;
    static _Thread_local rig_ctl_event_t ev[512];
    static _Thread_local rig_snapshot_t snap;
    uint64_t next = 0;
    while (!atomic_load(&writer_done)) {
        uint64_t lost = 0;
        size_t n = rig_ctl_events(&ctl, next, ev, 512u, &lost);
        next += lost;
        for (size_t i = 0; i < n; i++) {
            char want[32];
            (void)snprintf(want, sizeof want, "event %llu", (unsigned long long)ev[i].seq);
            if (ev[i].seq != next || ev[i].t_us != ev[i].seq || strcmp(ev[i].text, want) != 0) {
                atomic_fetch_add(&torn, 1u);
            }
            next = ev[i].seq + 1u;
        }
        rig_ctl_snapshot(&ctl, &snap);
        if (snap.num_cards != 2u || snap.cards[1].address != 5u) {
            atomic_fetch_add(&torn, 1u);
        }
    }
    return NULL;
}

static void test_readers_see_whole_events_and_snapshots(void)
{
    setup();
    rig_ctl_service(&ctl, 0u);
    atomic_store(&writer_done, false);
    atomic_store(&torn, 0u);
    pthread_t r[3];
    for (unsigned i = 0; i < 3u; i++) {
        CHECK_EQ(pthread_create(&r[i], NULL, event_reader, NULL), 0);
    }
    (void)event_writer(NULL);
    for (unsigned i = 0; i < 3u; i++) {
        pthread_join(r[i], NULL);
    }
    CHECK_EQ(atomic_load(&torn), 0u);
    CHECK_EQ(rig_ctl_next_seq(&ctl), 3u * RIG_CTL_EVENTS);
    teardown();
}

int main(void)
{
    RUN_TEST(test_queued_timeout_is_withdrawn);
    RUN_TEST(test_running_timeout_may_still_happen);
    RUN_TEST(test_dip_to_a_used_address_is_refused);
    RUN_TEST(test_ambiguous_address_is_refused);
    RUN_TEST(test_loop_never_waits_for_a_writer);
    RUN_TEST(test_readers_see_whole_events_and_snapshots);
    return check_report();
}
