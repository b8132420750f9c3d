#include "rig/rig.h"

#include <stdio.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>
#include "dp_slave/fdl_wire.h"
#include "sim_hal/host_clock.h"

/* ---- fan-out to the taps ------------------------------------------------------------------ */

#define FOR_TAPS(r, fn, ...)                                                                     \
    for (unsigned t_ = 0; t_ < (r)->num_taps; t_++) {                                            \
        if ((r)->taps[t_].fn != NULL) {                                                          \
            (r)->taps[t_].fn((r)->taps[t_].ctx, __VA_ARGS__);                                    \
        }                                                                                        \
    }

static void tap_frame(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                      uint32_t baud)
{
    rig_t *r = ctx;
    FOR_TAPS(r, frame, t_ns, frame, len, local, baud);
}

static void on_card_event(void *ctx, const dp_event_t *ev)
{
    rig_card_t *c = ctx;
    FOR_TAPS(c->rig, card_event, c->index, ev);
}

static void on_led(void *ctx, hal_led_id_t led, hal_led_mode_t mode)
{
    rig_card_t *c = ctx;
    FOR_TAPS(c->rig, led, c->index, led, mode);
}

static void on_param(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                     const uint8_t rsp[ML_TELEGRAM_LEN])
{
    rig_card_t *c = ctx;
    FOR_TAPS(c->rig, param, c->index, channel, req, rsp);
}

static void on_master_event(void *ctx, const dp_master_event_t *ev)
{
    rig_t *r = ctx;
    FOR_TAPS(r, master_event, ev);
}

static void on_ring_event(void *ctx, const fdl_active_event_t *ev)
{
    rig_t *r = ctx;
    FOR_TAPS(r, ring_event, ev);
}

static void drive_event(rig_card_t *c, rig_drive_event_type_t type, uint32_t value)
{
    const movidrive_t *md = &c->cs.md;
    rig_drive_event_t ev = {.type = type, .value = value, .speed_mrpm = md->speed_actual_mrpm,
                            .setpoint_mrpm = md->speed_setpoint_mrpm};
    FOR_TAPS(c->rig, drive, c->index, &ev);
}

/* The emulation has no event hook: its state after each poll is compared with the last one.
 * Ramps are told at their start, at each quarter of the way and at the end, which is what a
 * commissioning engineer watches on the drive's display. */
static void watch_drive(rig_card_t *c)
{
    if (c->cs.inverter != CARD_INVERTER_SIM) {
        return;
    }
    const movidrive_t *md = &c->cs.md;
    if (!c->w_known) {
        c->w_known = true;
        c->w_enabled = md->output_stage_enabled;
        c->w_fault = md->fault;
        c->w_target_mrpm = md->speed_actual_mrpm;
        return;
    }
    if (md->fault != c->w_fault) {
        if (md->fault != 0u) {
            drive_event(c, RIG_DRIVE_FAULT, md->fault);
        } else {
            drive_event(c, RIG_DRIVE_FAULT_RESET, c->w_fault);
        }
        c->w_fault = md->fault;
    }
    if (md->output_stage_enabled != c->w_enabled) {
        c->w_enabled = md->output_stage_enabled;
        drive_event(c, c->w_enabled ? RIG_DRIVE_ENABLED : RIG_DRIVE_INHIBITED, 0);
    }
    int32_t n = md->speed_actual_mrpm;
    int32_t target = md->output_stage_enabled ? md->speed_setpoint_mrpm : 0;
    if (n != target && (!c->w_ramping || target != c->w_target_mrpm)) {
        c->w_ramping = true;
        c->w_from_mrpm = n;
        c->w_target_mrpm = target;
        c->w_quarter = 0;
        drive_event(c, RIG_DRIVE_RAMP, 0);
        return;
    }
    if (!c->w_ramping) {
        return;
    }
    if (n == c->w_target_mrpm) {
        c->w_ramping = false;
        drive_event(c, RIG_DRIVE_SPEED, 1);
        return;
    }
    int64_t span = (int64_t)c->w_target_mrpm - c->w_from_mrpm;
    int64_t done = (int64_t)n - c->w_from_mrpm;
    if (span != 0) {
        int64_t q = done * 4 / span;
        if (q > c->w_quarter && q < 4) {
            c->w_quarter = (uint8_t)q;
            drive_event(c, RIG_DRIVE_SPEED, 0);
        }
    }
}

/* ---- a card behind its bus connector ------------------------------------------------------ */

static void card_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    rig_card_t *c = ctx;
    if (c->cable) {
        dfp21b_rx_char(&c->cs.card, byte, flags, t);
    }
}

/* The in-memory bus's telegram path (membus.h): the timestamps rx_char would have had. */
static dp_master_whole_t whole_of(const membus_telegram_t *tg)
{
    return (dp_master_whole_t){.data = tg->data, .len = (uint16_t)tg->len, .char_ns = tg->char_ns,
                         .first_t = membus_char_us(tg, 1u),
                         .before_last_t = membus_char_us(tg, tg->len > 1u ? tg->len - 1u : 1u),
                         .end_t = membus_char_us(tg, tg->len)};
}

/* A card off the bus (cable, or its own on_bus) hears nothing either way. */
static bool card_hears(const rig_card_t *c)
{
    return c->cable && c->cs.card.on_bus;
}

/* The octets' check (shape, FCS) is the same for every listener: the first one asked keeps
 * it in the telegram's memo (1 good, 2 bad) for the others. */
static bool octets_ok(const membus_telegram_t *tg, const dp_master_whole_t *w)
{
    if (*tg->memo == 0u) {
        *tg->memo = dp_master_whole_octets_ok(w) ? 1u : 2u;
    }
    return *tg->memo == 1u;
}

static bool card_takes_whole(void *ctx, const membus_telegram_t *tg)
{
    rig_card_t *c = ctx;
    dp_master_whole_t w = whole_of(tg);
    return !card_hears(c) || (dp_master_whole_fits(&c->cs.card.dp.rx, &w) && octets_ok(tg, &w));
}

/* Where a data telegram (SD1, SD2, SD3) carries DA; 0 for SD4 and SC, which carry none. */
static size_t data_da_at(uint8_t sd)
{
    if (sd == FDL_SD1 || sd == FDL_SD3) {
        return FDL_SD1_SD3_HEADER_LEN;
    }
    return sd == FDL_SD2 ? FDL_SD2_HEADER_LEN : 0u;
}

/* A clean telegram leaves a card that is not its addressee (fdl_station_frame: a token, a
 * short acknowledgement, a response, a request to another address) only its receiver's record
 * of the line (the last character's time, the frame served). Its poll would then find what it
 * found at its last one, except where that record or the line's activity is what it reads:
 * the rate still searched (the activity ends the search and sets the baud-control deadline),
 * the first error-free telegram since power-up or a baud loss (line_active: the BUS FAULT LED),
 * the first telegram after a second's silence (fdl_rx_poll's deadline to forget the last
 * character appears). With the emulated drive it is polled anyway: the drive's time advances
 * in steps from poll to poll, and their rounding follows the steps. */
static bool card_quiet(const rig_card_t *c, const membus_telegram_t *tg)
{
    const dp_slave_t *s = &c->cs.card.dp;
    if (!card_hears(c) || c->cs.inverter != CARD_INVERTER_NONE || !s->rx.have_last ||
        s->baud_state == DP_BAUD_SEARCH) {
        return false;
    }
    size_t da_at = data_da_at(tg->data[0]);
    if (da_at == 0u) {
        return true; /* SD4, SC: not data, not line activity */
    }
    if (!s->line_active) {
        return false;
    }
    uint8_t da = tg->data[da_at] & FDL_ADDR_MASK;
    uint8_t fc = tg->data[da_at + FDL_FC_FROM_DA];
    return (fc & FDL_FC_REQUEST) == 0u || (da != s->cfg.address && da != FDL_ADDR_BROADCAST);
}


/* A quiet telegram (card_quiet) reaches dp_slave_rx_telegram's station layer only to be
 * dropped there: fdl_station_frame notes line activity the card has already noted and finds
 * no request for it before touching anything. The receiver still takes it and the card frames
 * what it frames after any telegram, as dp_slave_rx_telegram does. */
static void card_rx_quiet(rig_card_t *c, const fdl_rx_telegram_t *t)
{
    dp_slave_t *s = &c->cs.card.dp;
    if (fdl_rx_telegram(&s->rx, t) == FDL_RX_FRAME) {
        dp_slave_prepare(s);
    } else { /* not reached: the octets were checked; the full path reports the error */
        dfp21b_rx_telegram(&c->cs.card, t);
    }
}

static bool card_rx_whole(void *ctx, const membus_telegram_t *tg)
{
    rig_card_t *c = ctx;
    if (!card_hears(c)) {
        return true;
    }
    bool quiet = !c->rig->cfg.every_telegram_to_cards && card_quiet(c, tg);
    dp_master_whole_t w = whole_of(tg);
    fdl_rx_telegram_t t = dp_master_whole_take(&c->cs.card.dp.rx, &w);
    if (quiet) {
        card_rx_quiet(c, &t);
        /* With the line active, every telegram but a request to its address or to all is
         * quiet for it (card_quiet), until something else reaches it: it sleeps through them
         * (telegram_key tells the bus which they are, card_catch_up reproduces them). */
        if (c->cs.card.dp.line_active && c->port != NULL) {
            membus_sleep(c->port, c->cs.card.dp.cfg.address);
        }
    } else {
        dfp21b_rx_telegram(&c->cs.card, &t);
    }
    return !quiet;
}

/* Quiet telegrams leave the receiver only the record of the last one (its end, its idle before,
 * the frame served): that one taken as card_rx_whole takes it, after the line's last character
 * before it (the card heard every telegram since it fell asleep), does all they did. */
static void card_catch_up(void *ctx, const membus_telegram_t *last,
                          const membus_telegram_t *before)
{
    rig_card_t *c = ctx;
    fdl_rx_t *rx = &c->cs.card.dp.rx;
    if (before != NULL) {
        rx->last_char_t = membus_char_us(before, before->len);
    }
    dp_master_whole_t w = whole_of(last);
    fdl_rx_telegram_t t = dp_master_whole_take(rx, &w);
    card_rx_quiet(c, &t);
}

/* Which sleeping card a telegram concerns (card_quiet's rule): a clean request's destination,
 * every card for a request to all or octets that are not one telegram, none for the rest. */
static uint8_t telegram_key(void *ctx, const membus_telegram_t *tg)
{
    (void)ctx;
    dp_master_whole_t w = whole_of(tg);
    if (!octets_ok(tg, &w)) {
        return MEMBUS_KEY_ALL;
    }
    size_t da_at = data_da_at(tg->data[0]);
    if (da_at == 0u) {
        return MEMBUS_KEY_NONE;
    }
    uint8_t da = tg->data[da_at] & FDL_ADDR_MASK;
    if ((tg->data[da_at + FDL_FC_FROM_DA] & FDL_FC_REQUEST) == 0u) {
        return MEMBUS_KEY_NONE;
    }
    return da == FDL_ADDR_BROADCAST ? MEMBUS_KEY_ALL : da;
}

static bool master_takes_whole(void *ctx, const membus_telegram_t *tg)
{
    dp_master_t *m = ctx;
    dp_master_whole_t w = whole_of(tg);
    return dp_master_whole_fits(&m->rx, &w) && octets_ok(tg, &w);
}

static bool master_rx_whole(void *ctx, const membus_telegram_t *tg)
{
    dp_master_whole_t w = whole_of(tg);
    dp_master_rx_telegram(ctx, &w);
    return true;
}

static hal_time_us_t card_poll(void *ctx, hal_time_us_t now)
{
    rig_card_t *c = ctx;
    sim_station_t st = card_station(&c->cs);
    hal_time_us_t next = st.poll(st.ctx, now);
    watch_drive(c);
    return next;
}

static int card_set_baud(void *ctx, uint32_t baud)
{
    rig_card_t *c = ctx;
    return c->medium_uart.ops->set_baud(c->medium_uart.ctx, baud);
}

/* A pulled connector: the card keeps transmitting into nothing. */
static int card_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    rig_card_t *c = ctx;
    if (!c->cable) {
        return 0;
    }
    return c->medium_uart.ops->transmit(c->medium_uart.ctx, frame, len, not_before);
}

static const hal_uart_ops_t card_uart_ops = {.set_baud = card_set_baud,
                                             .transmit = card_transmit};

/* Several cards on one tty or segment: one station for the medium that hands every character
 * to each card and polls them all (on a real line each card hears the whole bus too). */
static void cards_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    rig_t *r = ctx;
    for (unsigned i = 0; i < r->num_cards; i++) {
        card_rx(&r->cards[i], byte, flags, t);
    }
}

static hal_time_us_t earlier(hal_time_us_t a, hal_time_us_t b)
{
    return hal_time_diff(a, b) < 0 ? a : b;
}

/* The medium polls after every received telegram as well as at the deadline, and a card must
 * see both, so every card is polled on every call. */
static hal_time_us_t cards_poll(void *ctx, hal_time_us_t now)
{
    rig_t *r = ctx;
    hal_time_us_t next = now + 1000000u;
    for (unsigned i = 0; i < r->num_cards; i++) {
        next = earlier(next, card_poll(&r->cards[i], now));
    }
    return next;
}

/* ---- assembly ------------------------------------------------------------------------------ */

void rig_init(rig_t *r, const rig_cfg_t *cfg)
{
    memset(r, 0, sizeof *r);
    r->cfg = *cfg;
}

int rig_add_tap(rig_t *r, const rig_tap_t *tap)
{
    if (r->num_taps >= RIG_MAX_TAPS) {
        return -1;
    }
    r->taps[r->num_taps++] = *tap;
    return 0;
}

static bool wall_clock(const rig_t *r)
{
    return r->cfg.medium != RIG_MEDIUM_MEMBUS;
}

static void open_runner(rig_t *r)
{
    /* The loop waits in ppoll() for deadlines microseconds apart (the idle before a request is
     * 26 us at 1.5 Mbit/s); the kernel's default 50 us of timer slack would stretch each one. */
    (void)prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL);
    if (r->cfg.shared_runner != NULL) {
        r->runner = r->cfg.shared_runner;
        return;
    }
    r->runner = &r->own_runner;
    tty_runner_init(r->runner);
    if (r->cfg.medium == RIG_MEDIUM_TTY) {
        tty_runner_set_tap(r->runner, tap_frame, r);
    }
}

int rig_open(rig_t *r, char *err, size_t errlen)
{
    switch (r->cfg.medium) {
    case RIG_MEDIUM_MEMBUS:
        membus_init(&r->bus);
        r->bus.now_ns = r->cfg.start_ns;
        membus_set_tap(&r->bus, tap_frame, r);
        membus_set_key(&r->bus, telegram_key, NULL);
        break;
    case RIG_MEDIUM_TTY: {
        int rc = r->cfg.use_fd
                     ? tty_port_open_fd(&r->port, r->cfg.fd, r->cfg.baud, err, errlen)
                     : tty_port_open(&r->port, r->cfg.device, r->cfg.baud, err, errlen);
        if (rc != 0) {
            return -1;
        }
        r->port.echo_suppress = r->cfg.echo_suppress;
        open_runner(r);
        break;
    }
    case RIG_MEDIUM_LCM:
        if (dfp_lcm_segment_open(&r->segment, r->cfg.lcm_url, r->cfg.lcm_channel,
                                 r->cfg.lcm_station_address, r->cfg.baud, err, errlen) != 0) {
            return -1;
        }
        if (r->cfg.lcm_key != NULL && dfp_lcm_segment_set_key(&r->segment, r->cfg.lcm_key) != 0) {
            snprintf(err, errlen, "LCM segment %s: libsodium cannot start", r->cfg.lcm_channel);
            dfp_lcm_segment_close(&r->segment);
            return -1;
        }
        open_runner(r);
        dfp_lcm_segment_set_tap(&r->segment, tap_frame, r);
        break;
    }
    r->open = true;
    return 0;
}

/* A master in a token ring hands the token on before its medium closes (dp_master_leave), so the
 * other masters do not wait for the lost-token time-out; bounded by a reply still on its way and
 * the token's pass with its repeats (a successor refuses a new PS's first token), a slot time
 * each. */
static void master_leave(rig_t *r)
{
    if (!r->has_master || !wall_clock(r) || !r->master.cfg.token_ring) {
        return;
    }
    static const volatile int never = 0;
    dp_master_leave(&r->master);
    rig_wake(r);
    uint32_t slots = FDL_TOKEN_PASS_REPEATS + 3u;
    hal_time_us_t end = rig_now_us(r) + slots * r->master.cfg.slot_time_us;
    while (!dp_master_left(&r->master) && hal_time_diff(end, rig_now_us(r)) > 0) {
        if (rig_run_until(r, rig_now_us(r) + 2000u, &never) < 0) {
            return;
        }
    }
}

void rig_close(rig_t *r)
{
    if (!r->open) {
        return;
    }
    master_leave(r);
    r->open = false;
    if (r->cfg.medium == RIG_MEDIUM_TTY) {
        tty_port_close(&r->port);
    } else if (r->cfg.medium == RIG_MEDIUM_LCM) {
        dfp_lcm_segment_close(&r->segment);
    }
    for (unsigned i = 0; i < r->num_cards; i++) {
        card_station_close(&r->cards[i].cs);
    }
}

static hal_uart_t medium_uart(rig_t *r)
{
    return r->cfg.medium == RIG_MEDIUM_TTY ? tty_port_uart(&r->port)
                                           : dfp_lcm_segment_uart(&r->segment);
}

/* The wall-clock media know one station: the first card or the master attaches it. */
static int attach_wall_station(rig_t *r, const sim_station_t *st)
{
    if (r->cfg.medium == RIG_MEDIUM_TTY) {
        return tty_runner_add(r->runner, &r->port, st);
    }
    return dfp_lcm_segment_attach(&r->segment, r->runner, st);
}

rig_card_t *rig_add_card(rig_t *r, const card_options_t *opt, hal_time_us_t now)
{
    if (r->num_cards >= RIG_MAX_CARDS || (wall_clock(r) && (r->has_master || r->has_listener))) {
        return NULL;
    }
    rig_card_t *c = &r->cards[r->num_cards];
    memset(c, 0, sizeof *c);
    c->rig = r;
    c->index = r->num_cards;
    c->cable = true;
    c->opt = *opt;
    if (opt->eeprom_path != NULL) {
        snprintf(c->eeprom_path, sizeof c->eeprom_path, "%s", opt->eeprom_path);
        c->opt.eeprom_path = c->eeprom_path;
    }
    if (opt->card_nvm_path != NULL) {
        snprintf(c->card_nvm_path, sizeof c->card_nvm_path, "%s", opt->card_nvm_path);
        c->opt.card_nvm_path = c->card_nvm_path;
    }
    c->opt.event = on_card_event;
    c->opt.led_change = on_led;
    c->opt.ctx = c;
    c->opt.param_observer = on_param;
    c->opt.param_observer_ctx = c;
    c->next_address = opt->address;
    if (wall_clock(r)) {
        if (r->num_cards == 0u) {
            sim_station_t st = {.ctx = r, .rx_char = cards_rx, .poll = cards_poll};
            if (attach_wall_station(r, &st) != 0) {
                return NULL;
            }
        }
        c->medium_uart = medium_uart(r);
    } else {
        sim_station_t st = {.ctx = c, .rx_char = card_rx, .poll = card_poll};
        if (r->cfg.wrap_card_station != NULL) {
            st = r->cfg.wrap_card_station(r->cfg.wrap_ctx, st);
        }
        membus_port_t *port = membus_attach(&r->bus, &st, &c->medium_uart);
        if (port == NULL) {
            return NULL;
        }
        if (r->cfg.wrap_card_station == NULL) { /* a wrapper wants the characters */
            membus_whole_rx_t whole = {.ctx = c, .takes = card_takes_whole, .rx = card_rx_whole,
                                       .catch_up = card_catch_up};
            membus_set_whole_rx(port, &whole);
            c->port = port;
        }
    }
    if (r->cfg.wrap_card_uart != NULL) {
        c->medium_uart = r->cfg.wrap_card_uart(r->cfg.wrap_ctx, c->medium_uart);
    }
    r->num_cards++;
    hal_uart_t uart = {.ops = &card_uart_ops, .ctx = c};
    if (card_station_init(&c->cs, &c->opt, uart, now, c->nvm_note, sizeof c->nvm_note) != 0 &&
        c->nvm_note[0] == '\0') {
        snprintf(c->nvm_note, sizeof c->nvm_note, "non-volatile storage unusable");
    }
    watch_drive(c);
    return c;
}

int rig_attach_listener(rig_t *r, const sim_station_t *st)
{
    if (!wall_clock(r) || !r->open || r->num_cards > 0u || r->has_master || r->has_listener) {
        return -1;
    }
    if (attach_wall_station(r, st) != 0) {
        return -1;
    }
    r->has_listener = true;
    return 0;
}

int rig_attach_tester(rig_t *r, const sim_station_t *st, hal_uart_t *uart)
{
    if (!wall_clock(r)) {
        return membus_attach(&r->bus, st, uart) != NULL ? 0 : -1;
    }
    if (rig_attach_listener(r, st) != 0) {
        return -1;
    }
    *uart = medium_uart(r);
    return 0;
}

dp_master_t *rig_add_master(rig_t *r, const dp_master_cfg_t *cfg, hal_time_us_t now)
{
    if (r->has_master || (wall_clock(r) && (r->num_cards > 0u || r->has_listener))) {
        return NULL;
    }
    sim_station_t st = master_station(&r->master);
    dp_master_cfg_t mc = *cfg;
    mc.event = on_master_event;
    mc.ring_event = on_ring_event;
    mc.event_ctx = r;
    if (wall_clock(r)) {
        if (attach_wall_station(r, &st) != 0) {
            return NULL;
        }
        mc.uart = medium_uart(r);
    } else {
        r->master_port = membus_attach(&r->bus, &st, &mc.uart);
        if (r->master_port == NULL) {
            return NULL;
        }
        membus_whole_rx_t whole = {.ctx = &r->master, .takes = master_takes_whole,
                                   .rx = master_rx_whole};
        membus_set_whole_rx(r->master_port, &whole);
    }
    r->master_uart = mc.uart;
    dp_master_init(&r->master, &mc, now);
    r->has_master = true;
    return &r->master;
}

membus_port_t *rig_attach_station(rig_t *r, const sim_station_t *st, hal_uart_t *uart)
{
    return wall_clock(r) ? NULL : membus_attach(&r->bus, st, uart);
}

rig_card_t *rig_card_by_address(rig_t *r, uint8_t address)
{
    for (unsigned i = 0; i < r->num_cards; i++) {
        if (r->cards[i].cs.card.address == address) {
            return &r->cards[i];
        }
    }
    return NULL;
}

/* ---- hardware actions ---------------------------------------------------------------------- */

static void action(rig_card_t *c, rig_action_type_t type, uint32_t value)
{
    if (c->port != NULL) {
        membus_catch_up(c->port); /* the card changes: it must be up to date first */
    }
    FOR_TAPS(c->rig, action, c->index, type, value);
}

void rig_card_set_cable(rig_card_t *c, bool connected)
{
    if (c->cable != connected) {
        c->cable = connected;
        action(c, RIG_ACTION_CABLE, connected);
    }
}

/* The card restarts; its drive (which powers it in the real unit) runs on. */
void rig_card_power_cycle(rig_card_t *c, hal_time_us_t now)
{
    action(c, RIG_ACTION_POWER_CYCLE, c->next_address);
    c->cs.dip.switches = c->next_address;
    dfp21b_cfg_t cfg = c->cs.card.cfg;
    dfp21b_init(&c->cs.card, &cfg, now);
    if (c->cs.inverter == CARD_INVERTER_SIM) {
        movidrive_inproc_link_card_restarted(&c->cs.movidrive_link);
    }
    rig_wake(c->rig);
}

void rig_card_set_dip(rig_card_t *c, uint8_t address)
{
    c->next_address = address;
    action(c, RIG_ACTION_DIP, address);
}

void rig_card_set_input(rig_card_t *c, bool di00)
{
    if (c->cs.inverter != CARD_INVERTER_SIM) {
        return;
    }
    movidrive_set_terminal_enable(&c->cs.md, di00);
    drive_event(c, RIG_DRIVE_INPUT, di00);
    rig_wake(c->rig);
}

void rig_card_inject_fault(rig_card_t *c, uint8_t fault)
{
    if (c->cs.inverter != CARD_INVERTER_SIM) {
        return;
    }
    action(c, RIG_ACTION_FAULT_INJECTED, fault);
    movidrive_inject_fault(&c->cs.md, fault);
    rig_wake(c->rig);
}

void rig_wake(rig_t *r)
{
    if (wall_clock(r)) {
        tty_runner_wake(r->runner);
        for (uint8_t s = 0; s < r->runner->num_slots; s++) {
            r->runner->slots[s].deadline = tty_now_us();
        }
        return;
    }
    for (uint8_t i = 0; i < r->bus.num_ports; i++) {
        membus_wake(&r->bus.ports[i]);
    }
}

/* ---- running ------------------------------------------------------------------------------- */

hal_time_us_t rig_now_us(const rig_t *r)
{
    return wall_clock(r) ? tty_now_us() : membus_now_us(&r->bus);
}

uint64_t rig_elapsed_ns(const rig_t *r)
{
    switch (r->cfg.medium) {
    case RIG_MEDIUM_MEMBUS:
        return r->bus.now_ns;
    case RIG_MEDIUM_TTY:
        return host_clock_mono_ns() - r->runner->t0_ns;
    case RIG_MEDIUM_LCM:
        return host_clock_mono_ns() - r->segment.t0_ns;
    }
    return 0;
}

int rig_run_until(rig_t *r, hal_time_us_t t_us, volatile const int *stop)
{
    if (!wall_clock(r)) {
        uint64_t now_us = r->bus.now_ns / 1000u;
        int32_t d = hal_time_diff(t_us, (hal_time_us_t)now_us);
        if (d > 0) {
            membus_run_until_ns(&r->bus, r->bus.now_ns + (uint64_t)d * 1000u);
        }
        return 0;
    }
    return tty_runner_run_until(r->runner, t_us, stop);
}

const char *rig_error(const rig_t *r)
{
    return r->runner != NULL ? tty_runner_error(r->runner) : "";
}

int rig_add_fd(rig_t *r, int fd, tty_fd_readable_fn readable, void *ctx)
{
    return wall_clock(r) ? tty_runner_add_fd(r->runner, fd, readable, ctx) : 0;
}

int rig_add_timer(rig_t *r, tty_timer_fn poll, void *ctx)
{
    return wall_clock(r) ? tty_runner_add_timer(r->runner, poll, ctx) : 0;
}
