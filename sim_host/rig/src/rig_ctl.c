#include "rig/rig_ctl.h"

#include <errno.h>
#include <limits.h>
#include <linux/futex.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include "dp_master/param_channel.h"
#include "rig_ctl_param.h"
#include "dp_slave/dp_wire.h"
#include "sim_hal/host_clock.h"

#define SERVICE_TIMEOUT_US 5000000u

/* ---- waking clients ------------------------------------------------------------------------ */

/* Whoever changes what a client waits for calls this afterwards. It never blocks: FUTEX_WAKE
 * only makes sleepers runnable, and it is skipped when nobody waits. A client that is about to
 * sleep cannot miss it: it counts itself in waiters before it reads gen, and futex_wait
 * returns at once when gen is no longer what it read (both sides seq_cst). */
static void wake_clients(rig_ctl_t *c)
{
    atomic_fetch_add(&c->gen, 1u);
    if (atomic_load(&c->waiters) > 0u) {
        (void)syscall(SYS_futex, &c->gen, FUTEX_WAKE_PRIVATE, INT_MAX, NULL, NULL, 0);
    }
}

void rig_ctl_kick(rig_ctl_t *c)
{
    wake_clients(c);
}

static uint64_t ms_since(uint64_t t0_ns)
{
    return (host_clock_mono_ns() - t0_ns) / 1000000u;
}

/* Sleeps until ready(c, arg), the close or timeout_ms; returns ready's last answer. */
static bool wait_until(rig_ctl_t *c, bool (*ready)(rig_ctl_t *, uint64_t), uint64_t arg,
                       unsigned timeout_ms)
{
    uint64_t t0 = host_clock_mono_ns();
    bool ok = false;
    atomic_fetch_add(&c->waiters, 1u);
    for (;;) {
        unsigned g = atomic_load(&c->gen);
        ok = ready(c, arg);
        uint64_t spent = ms_since(t0);
        if (ok || atomic_load(&c->closing) || spent >= timeout_ms) {
            break;
        }
        uint64_t left = timeout_ms - spent;
        struct timespec rel = {(time_t)(left / 1000u), (long)(left % 1000u) * 1000000L};
        (void)syscall(SYS_futex, &c->gen, FUTEX_WAIT_PRIVATE, g, &rel, NULL, 0);
    }
    atomic_fetch_sub(&c->waiters, 1u);
    return ok;
}

int rig_ctl_init(rig_ctl_t *c, rig_t *r, const char *mode, bool read_only)
{
    memset(c, 0, sizeof *c);
    c->rig = r;
    c->mode = mode;
    c->read_only = read_only;
    c->active_slot = -1;
    c->wake_fd = -1;
    c->loop_thread = pthread_self();
    atomic_init(&c->closing, false);
    atomic_init(&c->gen, 0u);
    atomic_init(&c->waiters, 0u);
    atomic_init(&c->snap_current, 0u);
    atomic_init(&c->next_seq, 0u);
    atomic_init(&c->now_us, 0u);
    for (unsigned i = 0; i < RIG_CTL_SNAPS; i++) {
        atomic_init(&c->snap_use[i], 0u);
    }
    for (unsigned i = 0; i < RIG_CTL_CMDS; i++) {
        atomic_init(&c->slot[i], RIG_SLOT_FREE);
    }
    if (pthread_mutex_init(&c->ev_lock, NULL) != 0) {
        return -1;
    }
    c->wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    return c->wake_fd < 0 ? -1 : 0;
}

void rig_ctl_destroy(rig_ctl_t *c)
{
    atomic_store(&c->closing, true);
    wake_clients(c);
    if (c->wake_fd >= 0) {
        close(c->wake_fd);
        c->wake_fd = -1;
    }
}

static void drain_wake(void *ctx, hal_time_us_t now)
{
    (void)now;
    rig_ctl_t *c = ctx;
    uint64_t v;
    while (read(c->wake_fd, &v, sizeof v) == (ssize_t)sizeof v) {
    }
    rig_ctl_service(c, 0);
}

int rig_ctl_attach(rig_ctl_t *c)
{
    return rig_add_fd(c->rig, c->wake_fd, drain_wake, c);
}

/* ---- events -------------------------------------------------------------------------------- */

static void copy_text(char *dst, size_t n, const char *src)
{
    snprintf(dst, n, "%s", src != NULL ? src : "");
}

/* Appends e as the next event; the caller holds ev_lock, so writers come one at a time. */
static void ring_put(rig_ctl_t *c, const rig_ctl_event_t *e)
{
    uint64_t seq = atomic_load_explicit(&c->next_seq, memory_order_relaxed);
    rig_ctl_ev_slot_t *sl = &c->ring[seq % RIG_CTL_EVENTS];
    uint64_t w[RIG_CTL_EVENT_WORDS] = {0};
    rig_ctl_event_t copy = *e;
    copy.seq = seq;
    memcpy(w, &copy, sizeof copy);
    atomic_store_explicit(&sl->stamp, 2u * seq + 1u, memory_order_relaxed);
    atomic_thread_fence(memory_order_release);
    for (size_t i = 0; i < RIG_CTL_EVENT_WORDS; i++) {
        atomic_store_explicit(&sl->words[i], w[i], memory_order_relaxed);
    }
    atomic_store_explicit(&sl->stamp, 2u * seq + 2u, memory_order_release);
    atomic_store_explicit(&c->next_seq, seq + 1u, memory_order_release);
}

/* Copies event seq; false when its entry holds a later one (overwritten, also while copied). */
static bool ring_get(rig_ctl_t *c, uint64_t seq, rig_ctl_event_t *out)
{
    rig_ctl_ev_slot_t *sl = &c->ring[seq % RIG_CTL_EVENTS];
    uint64_t want = 2u * seq + 2u;
    if (atomic_load_explicit(&sl->stamp, memory_order_acquire) != want) {
        return false;
    }
    uint64_t w[RIG_CTL_EVENT_WORDS];
    for (size_t i = 0; i < RIG_CTL_EVENT_WORDS; i++) {
        w[i] = atomic_load_explicit(&sl->words[i], memory_order_relaxed);
    }
    atomic_thread_fence(memory_order_acquire);
    if (atomic_load_explicit(&sl->stamp, memory_order_relaxed) != want) {
        return false;
    }
    memcpy(out, w, sizeof *out);
    return true;
}

/* Loop side: moves the staged events into the ring when no other writer is at it. */
static void flush_staged(rig_ctl_t *c)
{
    if ((c->staged_n == 0u && c->staged_dropped == 0u) ||
        !pthread_equal(pthread_self(), c->loop_thread) ||
        pthread_mutex_trylock(&c->ev_lock) != 0) {
        return;
    }
    for (unsigned i = 0; i < c->staged_n; i++) {
        ring_put(c, &c->staged[i]);
    }
    if (c->staged_dropped > 0u) {
        rig_ctl_event_t e = {.t_us = c->staged[c->staged_n - 1u].t_us, .level = RIG_LOG_WARN};
        copy_text(e.source, sizeof e.source, "sim");
        copy_text(e.kind, sizeof e.kind, "lost");
        (void)snprintf(e.text, sizeof e.text, "%llu log events dropped while the log was busy",
                       (unsigned long long)c->staged_dropped);
        ring_put(c, &e);
    }
    c->staged_n = 0;
    c->staged_dropped = 0;
    pthread_mutex_unlock(&c->ev_lock);
    wake_clients(c);
}

void rig_ctl_event(rig_ctl_t *c, uint64_t t_us, rig_log_level_t level, const char *source,
                   const char *kind, const char *text)
{
    rig_ctl_event_t e = {.t_us = t_us, .level = level};
    copy_text(e.source, sizeof e.source, source);
    copy_text(e.kind, sizeof e.kind, kind);
    copy_text(e.text, sizeof e.text, text);
    if (!pthread_equal(pthread_self(), c->loop_thread)) {
        pthread_mutex_lock(&c->ev_lock);
        ring_put(c, &e);
        pthread_mutex_unlock(&c->ev_lock);
        wake_clients(c);
        return;
    }
    /* Staged even when the queue is empty: one path keeps the loop's events in order. The
     * queue always has room for one (it was emptied, or the last one dropped is counted). */
    if (c->staged_n < RIG_CTL_STAGED) {
        c->staged[c->staged_n++] = e;
    } else {
        c->staged_dropped++;
    }
    flush_staged(c);
}

size_t rig_ctl_events(rig_ctl_t *c, uint64_t since, rig_ctl_event_t *out, size_t max,
                      uint64_t *lost)
{
    uint64_t next = atomic_load_explicit(&c->next_seq, memory_order_acquire);
    uint64_t oldest = next > RIG_CTL_EVENTS ? next - RIG_CTL_EVENTS : 0u;
    *lost = 0;
    if (since < oldest) {
        *lost = oldest - since;
        since = oldest;
    }
    /* Stops at an entry overwritten meanwhile: the caller asks again from there and is then
     * told it lost it. */
    size_t n = 0;
    for (uint64_t s = since; s < next && n < max && ring_get(c, s, &out[n]); s++) {
        n++;
    }
    return n;
}

uint64_t rig_ctl_next_seq(rig_ctl_t *c)
{
    return atomic_load_explicit(&c->next_seq, memory_order_acquire);
}

static bool seq_reached(rig_ctl_t *c, uint64_t since)
{
    return rig_ctl_next_seq(c) > since;
}

void rig_ctl_wait(rig_ctl_t *c, uint64_t since, unsigned timeout_ms)
{
    (void)wait_until(c, seq_reached, since, timeout_ms);
}

/* ---- snapshot ------------------------------------------------------------------------------ */

static void snap_card(const rig_card_t *rc, rig_snap_card_t *s)
{
    const dfp21b_t *card = &rc->cs.card;
    const dp_slave_t *dp = &card->dp;
    memset(s, 0, sizeof *s);
    s->address = card->address;
    s->next_address = rc->next_address;
    s->cable = rc->cable;
    s->on_bus = card->on_bus;
    s->dp_state = (uint8_t)dp_slave_state(dp);
    s->baud_state = (uint8_t)dp_slave_baud_state(dp);
    s->baud = dfp21b_p092_baud(card);
    s->master = -1;
    if (dp->master_add != DP_MASTER_ADD_NONE) {
        s->master = (int16_t)dp->master_add;
    }
    s->watchdog_ms = dp->wd_on ? dp->wd_time_ms : 0u;
    s->cfg_len = dp->cfg_len < sizeof s->cfg ? dp->cfg_len : (uint8_t)sizeof s->cfg;
    memcpy(s->cfg, dp->cfg_data, s->cfg_len);
    s->diag_len = (uint8_t)dp_slave_build_diag(dp, s->diag, sizeof s->diag);
    for (unsigned i = 0; i < HAL_LED_COUNT; i++) {
        s->led[i] = (uint8_t)rc->cs.leds.mode[i];
    }
    dfp21b_p090_text(&card->pd, s->p090, sizeof s->p090);
    s->pd_words = card->pd.valid ? card->pd.pd_words : 0u;
    memcpy(s->po, card->po, sizeof s->po);
    memcpy(s->pi, card->pi, sizeof s->pi);
    s->p819_ms = card->p819_ms;
    s->dpv1_enabled = dp_slave_dpv1_mode(dp);
    s->msac1_open = card->dpv1.c1.open;
    for (unsigned i = 0; i < 2u && i < DPV1_C2_CONNECTIONS; i++) {
        s->msac2_open[i] = card->dpv1.c2[i].open;
        s->msac2_master[i] = -1;
        if (card->dpv1.c2[i].open) {
            s->msac2_master[i] = (int16_t)card->dpv1.c2[i].master;
        }
    }
    copy_text(s->nvm_note, sizeof s->nvm_note, rc->cs.nvm_note); /* in full, not rig_card_t's cut */
    copy_text(s->eeprom_path, sizeof s->eeprom_path, rc->opt.eeprom_path);
    copy_text(s->card_nvm_path, sizeof s->card_nvm_path, rc->opt.card_nvm_path);
    if (rc->cs.inverter == CARD_INVERTER_SIM) {
        const movidrive_t *md = &rc->cs.md;
        int32_t v = 0;
        s->has_drive = true;
        s->control_word = md->control_word;
        s->status_word = movidrive_status_word(md);
        s->enabled = md->output_stage_enabled;
        s->fault = md->fault;
        s->setpoint_mrpm = md->speed_setpoint_mrpm;
        s->speed_mrpm = md->speed_actual_mrpm;
        s->current_mpct = md->current_mpct;
        s->ramp_up_ms = movidrive_read_value(md, MOVIDRIVE_IDX_P130_RAMP_UP, &v) ? v : 0;
        s->ramp_down_ms = movidrive_read_value(md, MOVIDRIVE_IDX_P131_RAMP_DOWN, &v) ? v : 0;
        s->di00 = md->cfg.terminal_enable;
    }
}

static void snap_slave(const dp_master_slave_t *sl, rig_snap_slave_t *s)
{
    memset(s, 0, sizeof *s);
    s->address = sl->cfg.address;
    s->phase = (uint8_t)sl->phase;
    s->cycles = sl->cycles;
    s->out_len = sl->out_len < sizeof s->outputs ? sl->out_len : (uint16_t)sizeof s->outputs;
    memcpy(s->outputs, sl->outputs, s->out_len);
    s->in_len = sl->inputs_len < sizeof s->inputs ? sl->inputs_len : (uint16_t)sizeof s->inputs;
    memcpy(s->inputs, sl->inputs, s->in_len);
    s->param_channel = rig_ctl_has_param_channel(sl);
    s->diag_len = sl->last_diag_len < sizeof s->diag ? sl->last_diag_len
                                                     : (uint8_t)sizeof s->diag;
    memcpy(s->diag, sl->last_diag, s->diag_len);
}

static const char *medium_text(const rig_t *r, char *buf, size_t n)
{
    switch (r->cfg.medium) {
    case RIG_MEDIUM_MEMBUS:
        return "in-memory bus";
    case RIG_MEDIUM_TTY:
        return r->cfg.device;
    case RIG_MEDIUM_LCM:
        snprintf(buf, n, "LCM segment %s", r->cfg.lcm_channel);
        return buf;
    }
    return "";
}

/* A buffer no client is copying, marked as being filled; -1 when every one but the current is
 * being read (the publication waits for the next turn). */
static int snap_claim(rig_ctl_t *c)
{
    unsigned cur = atomic_load_explicit(&c->snap_current, memory_order_relaxed);
    for (unsigned i = 0; i < RIG_CTL_SNAPS; i++) {
        unsigned idle = 0u;
        if (i != cur && atomic_compare_exchange_strong_explicit(
                            &c->snap_use[i], &idle, RIG_CTL_SNAP_WRITER, memory_order_acquire,
                            memory_order_relaxed)) {
            return (int)i;
        }
    }
    return -1;
}

static bool publish(rig_ctl_t *c)
{
    int b = snap_claim(c);
    if (b < 0) {
        c->snaps_skipped++;
        return false;
    }
    rig_snapshot_t *sp = &c->snaps[b];
    const rig_t *r = c->rig;
    char buf[96];
    memset(sp, 0, offsetof(rig_snapshot_t, cards));
    sp->t_us = rig_elapsed_ns(r) / 1000u;
    atomic_store_explicit(&c->now_us, sp->t_us, memory_order_relaxed);
    sp->medium = (uint8_t)r->cfg.medium;
    copy_text(sp->medium_name, sizeof sp->medium_name, medium_text(r, buf, sizeof buf));
    sp->num_cards = (uint8_t)r->num_cards;
    for (unsigned i = 0; i < r->num_cards; i++) {
        snap_card(&r->cards[i], &sp->cards[i]);
    }
    sp->medium_baud = r->num_cards > 0u ? sp->cards[0].baud : r->cfg.baud;
    sp->has_master = r->has_master;
    if (r->has_master) {
        const dp_master_t *m = &r->master;
        sp->master_address = m->cfg.address;
        sp->master_running = m->running;
        sp->master_baud = m->cfg.baud;
        sp->medium_baud = m->cfg.baud;
        sp->num_slaves = m->num_slaves;
        for (unsigned i = 0; i < m->num_slaves; i++) {
            snap_slave(&m->slaves[i], &sp->slaves[i]);
        }
    }
    atomic_fetch_sub_explicit(&c->snap_use[b], RIG_CTL_SNAP_WRITER, memory_order_release);
    atomic_store_explicit(&c->snap_current, (unsigned)b, memory_order_release);
    return true;
}

uint64_t rig_ctl_time_us(rig_ctl_t *c)
{
    return atomic_load_explicit(&c->now_us, memory_order_relaxed);
}

/* Pins the current buffer and copies it. A buffer the loop has claimed meanwhile is let go and
 * the new current one taken; a pinned buffer is never claimed, so the copy is of one whole
 * publication. */
void rig_ctl_snapshot(rig_ctl_t *c, rig_snapshot_t *out)
{
    for (;;) {
        unsigned i = atomic_load_explicit(&c->snap_current, memory_order_acquire);
        unsigned use = atomic_fetch_add_explicit(&c->snap_use[i], 1u, memory_order_acquire);
        if ((use & RIG_CTL_SNAP_WRITER) == 0u) {
            memcpy(out, &c->snaps[i], sizeof *out);
            atomic_fetch_sub_explicit(&c->snap_use[i], 1u, memory_order_release);
            return;
        }
        atomic_fetch_sub_explicit(&c->snap_use[i], 1u, memory_order_release);
    }
}

/* ---- commands ------------------------------------------------------------------------------ */

/* The client stops waiting. A command the loop has not taken up is withdrawn, so it is never
 * carried out and its slot is free at once. One already running cannot be called back; the loop
 * frees it when it ends. One that ended meanwhile is the client's after all: true. */
static bool give_up(rig_ctl_t *c, int k, rig_cmd_t *cmd, unsigned timeout_ms)
{
    int seen = RIG_SLOT_QUEUED;
    if (atomic_compare_exchange_strong_explicit(&c->slot[k], &seen, RIG_SLOT_FREE,
                                                memory_order_acq_rel, memory_order_acquire)) {
        cmd->status = 504;
        snprintf(cmd->error, sizeof cmd->error, "the simulation did not take the action up "
                 "within %u ms; it was withdrawn and not carried out", timeout_ms);
        return false;
    }
    seen = RIG_SLOT_RUNNING;
    if (atomic_compare_exchange_strong_explicit(&c->slot[k], &seen, RIG_SLOT_ABANDONED,
                                                memory_order_acq_rel, memory_order_acquire)) {
        cmd->status = 504;
        snprintf(cmd->error, sizeof cmd->error, "no answer within %u ms; the action may still "
                 "be carried out", timeout_ms);
        return false;
    }
    return seen == RIG_SLOT_DONE;
}

static bool slot_done(rig_ctl_t *c, uint64_t k)
{
    return atomic_load_explicit(&c->slot[k], memory_order_acquire) == RIG_SLOT_DONE;
}

bool rig_ctl_submit(rig_ctl_t *c, rig_cmd_t *cmd, unsigned timeout_ms)
{
    int k = -1;
    for (unsigned i = 0; i < RIG_CTL_CMDS && k < 0 && !atomic_load(&c->closing); i++) {
        int idle = RIG_SLOT_FREE;
        if (atomic_compare_exchange_strong_explicit(&c->slot[i], &idle, RIG_SLOT_FILLING,
                                                    memory_order_acquire,
                                                    memory_order_relaxed)) {
            k = (int)i;
        }
    }
    if (k < 0) {
        cmd->status = 503;
        snprintf(cmd->error, sizeof cmd->error, "too many actions waiting; try again");
        return false;
    }
    c->cmds[k] = *cmd;
    atomic_store_explicit(&c->slot[k], RIG_SLOT_QUEUED, memory_order_release);
    uint64_t one = 1;
    if (write(c->wake_fd, &one, sizeof one) < 0) {
        /* The loop also looks at the queue on every turn; the wake-up only makes it sooner. */
    }
    bool done = wait_until(c, slot_done, (uint64_t)k, timeout_ms) ||
                give_up(c, k, cmd, timeout_ms);
    if (done) {
        *cmd = c->cmds[k];
        atomic_store_explicit(&c->slot[k], RIG_SLOT_FREE, memory_order_release);
    }
    return done;
}

static void run_card_param(rig_card_t *rc, rig_cmd_t *cmd)
{
    if (rc->cs.inverter != CARD_INVERTER_SIM) {
        rig_cmd_fail(cmd, 409, "this card has no emulated drive (--inverter none or an SBus link)");
        return;
    }
    uint8_t req[ML_TELEGRAM_LEN] = {0};
    uint8_t rsp[ML_TELEGRAM_LEN];
    uint8_t service = cmd->type == RIG_CMD_PARAM_READ ? ML_SVC_READ
                      : cmd->flag                     ? ML_SVC_WRITE_VOLATILE
                                                      : ML_SVC_WRITE;
    dp_master_param_t build = {0};
    dp_master_param_start(&build, service, cmd->index, (uint32_t)cmd->value, req);
    movidrive_param(&rc->cs.md, req, rsp);
    cmd->status = 200;
    if ((rsp[0] & ML_MGMT_ERROR) != 0u) {
        cmd->refused = true;
        ml_error_text(rsp, cmd->error, sizeof cmd->error);
        return;
    }
    cmd->result = (int32_t)ml_data(rsp);
    rig_wake(rc->rig);
}

static void set_slave_words(dp_master_t *m, unsigned idx, const rig_cmd_t *cmd)
{
    dp_master_slave_t *sl = &m->slaves[idx];
    uint8_t out[DP_MASTER_MAX_IO];
    memcpy(out, sl->outputs, sl->out_len);
    size_t base = rig_ctl_has_param_channel(sl) ? ML_TELEGRAM_LEN : 0u;
    for (unsigned w = 0; w < cmd->num_words; w++) {
        size_t at = base + (size_t)2u * w;
        if (at + 1u < sl->out_len) {
            out[at] = (uint8_t)(cmd->words[w] >> 8);
            out[at + 1u] = (uint8_t)cmd->words[w];
        }
    }
    dp_master_set_outputs(m, idx, out, sl->out_len);
}

static void run_master_outputs(dp_master_t *m, rig_cmd_t *cmd)
{
    int idx = rig_ctl_slave_index(m, cmd->card);
    if (idx < 0) {
        rig_cmd_fail(cmd, 404, "the master has no slave with that address");
        return;
    }
    dp_master_slave_t *sl = &m->slaves[idx];
    if (cmd->raw_given) {
        if (cmd->raw_len != sl->out_len) {
            cmd->status = 400;
            (void)snprintf(cmd->error, sizeof cmd->error,
                           "hex: %u octets given, the slave's outputs are %u octets",
                           cmd->raw_len, sl->out_len);
            return;
        }
        dp_master_set_outputs(m, (unsigned)idx, cmd->raw, cmd->raw_len);
    } else {
        size_t base = rig_ctl_has_param_channel(sl) ? ML_TELEGRAM_LEN : 0u;
        if (base + (size_t)2u * cmd->num_words > sl->out_len) {
            cmd->status = 400;
            (void)snprintf(cmd->error, sizeof cmd->error,
                           "po: %u words given, the slave takes %u PO words", cmd->num_words,
                           (unsigned)((sl->out_len - base) / 2u));
            return;
        }
        set_slave_words(m, (unsigned)idx, cmd);
    }
    cmd->status = 200;
}

static void run_master_cmd(rig_ctl_t *c, rig_cmd_t *cmd, int k)
{
    rig_t *r = c->rig;
    if (!r->has_master) {
        rig_cmd_fail(cmd, 409, "this process has no master (use dfp-sim master or demo)");
        return;
    }
    switch (cmd->type) {
    case RIG_CMD_MASTER_RUN:
        if (cmd->flag && !r->master.running) {
            dp_master_start(&r->master, rig_now_us(r));
        } else if (!cmd->flag && r->master.running) {
            dp_master_stop(&r->master);
        }
        rig_wake(r);
        cmd->status = 200;
        return;
    case RIG_CMD_MASTER_OUTPUTS:
        run_master_outputs(&r->master, cmd);
        return;
    default:
        break;
    }
    /* RIG_CMD_MASTER_PARAM: one at a time, like a PLC's parameter block */
    if (c->active_slot >= 0) {
        rig_cmd_fail(cmd, 409, "another parameter service is running; try again");
        return;
    }
    if (rig_ctl_param_start(c, cmd)) {
        c->active_slot = k;
        c->slot_deadline_us[k] = rig_elapsed_ns(r) / 1000u + SERVICE_TIMEOUT_US;
    }
}

/* The HTTP routes refuse an ambiguous address from the snapshot, which may be a publish
 * behind a power cycle; the loop's own count is the one that decides. */
static unsigned cards_at(const rig_t *r, uint8_t address)
{
    unsigned n = 0;
    for (unsigned i = 0; i < r->num_cards; i++) {
        n += r->cards[i].cs.card.address == address ? 1u : 0u;
    }
    return n;
}

/* A DIP address another card of the line answers to now or after its power cycle is refused:
 * once two cards shared an address, no /cards/N route could tell them apart again (409), so
 * the line could not be put right without a restart. */
static bool dip_address_free(rig_t *r, const rig_card_t *rc, rig_cmd_t *cmd)
{
    for (unsigned i = 0; i < r->num_cards; i++) {
        const rig_card_t *o = &r->cards[i];
        if (o != rc && (o->cs.card.address == cmd->value || o->next_address == cmd->value)) {
            (void)snprintf(cmd->error, sizeof cmd->error,
                           "card %u of the line answers to address %ld%s: two cards must not "
                           "share an address",
                           i + 1u, (long)cmd->value,
                           o->cs.card.address == cmd->value ? "" : " after its power cycle");
            cmd->status = 409;
            return false;
        }
    }
    return true;
}

static void run_cmd(rig_ctl_t *c, rig_cmd_t *cmd, int k)
{
    rig_t *r = c->rig;
    cmd->status = 200;
    if (cmd->type >= RIG_CMD_MASTER_RUN) {
        run_master_cmd(c, cmd, k);
        return;
    }
    rig_card_t *rc = rig_card_by_address(r, cmd->card);
    if (rc == NULL) {
        rig_cmd_fail(cmd, 404, "no card with that address");
        return;
    }
    unsigned same = cards_at(r, cmd->card);
    if (same > 1u) {
        cmd->status = 409;
        (void)snprintf(cmd->error, sizeof cmd->error, RIG_CTL_AMBIGUOUS_FMT, same, cmd->card);
        return;
    }
    bool needs_drive = cmd->type == RIG_CMD_INPUTS || cmd->type == RIG_CMD_FAULT;
    if (needs_drive && rc->cs.inverter != CARD_INVERTER_SIM) {
        rig_cmd_fail(cmd, 409, "this card has no emulated drive (--inverter none or an SBus link)");
        return;
    }
    switch (cmd->type) {
    case RIG_CMD_INPUTS:
        rig_card_set_input(rc, cmd->flag);
        break;
    case RIG_CMD_FAULT:
        rig_card_inject_fault(rc, (uint8_t)cmd->value);
        break;
    case RIG_CMD_CABLE:
        rig_card_set_cable(rc, cmd->flag);
        break;
    case RIG_CMD_POWER_CYCLE:
        rig_card_power_cycle(rc, rig_now_us(r));
        break;
    case RIG_CMD_DIP:
        if (dip_address_free(r, rc, cmd)) {
            rig_card_set_dip(rc, (uint8_t)cmd->value);
        }
        break;
    case RIG_CMD_PARAM_READ:
    case RIG_CMD_PARAM_WRITE:
        run_card_param(rc, cmd);
        break;
    default:
        break;
    }
}

/* The loop hands the result back (DONE), or frees the slot of a client that gave up. */
static void finish(rig_ctl_t *c, int k)
{
    int seen = RIG_SLOT_RUNNING;
    if (!atomic_compare_exchange_strong_explicit(&c->slot[k], &seen, RIG_SLOT_DONE,
                                                 memory_order_release, memory_order_relaxed)) {
        atomic_store_explicit(&c->slot[k], RIG_SLOT_FREE, memory_order_release);
    }
    wake_clients(c);
}

/* The running master parameter service. Its command stays in the slot, which the loop owns
 * until it ends: a class-2 service has its answer before the connection is closed. */
static void advance_active(rig_ctl_t *c)
{
    int k = c->active_slot;
    rig_cmd_t *cmd = &c->cmds[k];
    bool done = rig_ctl_param_advance(c, cmd);
    if (!done && rig_elapsed_ns(c->rig) / 1000u > c->slot_deadline_us[k]) {
        cmd->status = 504;
        (void)snprintf(cmd->error, sizeof cmd->error, "no answer from slave %u within 5 s",
                       cmd->card);
        rig_ctl_param_give_up(c);
        done = true;
    }
    if (done) {
        c->active_slot = -1;
        finish(c, k);
    }
}

void rig_ctl_service(rig_ctl_t *c, uint64_t publish_every_ns)
{
    flush_staged(c);
    /* A queued command becomes the loop's by one compare-exchange: nothing to wait for. */
    for (int k = 0; k < (int)RIG_CTL_CMDS; k++) {
        int seen = RIG_SLOT_QUEUED;
        if (!atomic_compare_exchange_strong_explicit(&c->slot[k], &seen, RIG_SLOT_RUNNING,
                                                     memory_order_acquire,
                                                     memory_order_relaxed)) {
            continue;
        }
        run_cmd(c, &c->cmds[k], k);
        if (c->active_slot != k) {
            finish(c, k);
        }
    }
    if (c->active_slot >= 0) {
        advance_active(c);
    }
    uint64_t now = host_clock_mono_ns();
    if (publish_every_ns == 0u || now - c->last_publish_ns >= publish_every_ns) {
        if (publish(c)) {
            c->last_publish_ns = now;
        }
    }
}
