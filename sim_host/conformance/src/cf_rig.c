/* The suite's link over a rig (cf_rig.h). */
#include "conformance/cf_rig.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include "dp_slave/fdl_frame.h"
#include "fdl_active/fdl_active.h"

/* Unix 98 PTY slaves have majors 136..143: no baud rate, no timing. */
#define PTY_MAJOR_FIRST 136u
#define PTY_MAJOR_LAST 143u
/* After the last character of an answer: how long the line must stay quiet before a
 * telegram that makes no sense is taken as garbage, in characters. */
#define GARBLE_QUIET_CHARS 4u
/* The same on a wall-clock medium, which hands characters over in batches. */
#define WALL_QUIET_US 20000u
#define CF_RIG_WALL_RETRIES 2u

/* ---- the tester as a station -------------------------------------------------------------- */

/* The octets a telegram starting with rx[0] has, 0 while not known yet, SIZE_MAX for a first
 * octet that starts none. */
static size_t telegram_len(const uint8_t *rx, size_t n)
{
    switch (rx[0]) {
    case FDL_SC: return FDL_SC_LEN;
    case FDL_SD1: return FDL_SD1_LEN;
    case FDL_SD3: return FDL_SD3_LEN;
    case FDL_SD4: return FDL_SD4_LEN;
    case FDL_SD2: return n < 2u ? 0u : (size_t)rx[1] + FDL_SD2_OVERHEAD;
    default: return SIZE_MAX;
    }
}

static void tester_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    cf_rig_t *cr = ctx;
    (void)flags;
    cr->last_rx_t = t;
    cr->heard_any = true;
    cr->rx_chars++;
    if (!cr->listening) {
        return;
    }
    if (cr->rx_len < sizeof cr->rx) {
        cr->rx[cr->rx_len++] = byte;
    } else {
        cr->rx_overflow = true;
    }
    size_t want = telegram_len(cr->rx, cr->rx_len);
    if (want != 0u && want != SIZE_MAX && cr->rx_len >= want) {
        cr->done = 1;
    }
}

static hal_time_us_t tester_poll(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    return now + 1000000u;
}

static void tester_tap(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                       uint32_t baud)
{
    cf_rig_t *cr = ctx;
    (void)frame;
    (void)local;
    uint64_t end = t_ns + (uint64_t)len * hal_uart_char_ns(baud);
    if (end > cr->line_free_ns) {
        cr->line_free_ns = end;
    }
    if (!cr->listening) {
        return;
    }
    if (!cr->tx_seen) {
        cr->tx_seen = true;
        cr->tx_start_ns = t_ns;
    } else if (!cr->rx_seen) {
        cr->rx_seen = true;
        cr->rx_start_ns = t_ns;
    }
}

/* ---- the link ----------------------------------------------------------------------------- */

static bool wall(const cf_rig_t *cr)
{
    return cr->cfg.medium != RIG_MEDIUM_MEMBUS;
}

static uint64_t link_now_ns(void *ctx)
{
    cf_rig_t *cr = ctx;
    return rig_elapsed_ns(&cr->rig);
}

static int run_for_us(cf_rig_t *cr, uint32_t us, volatile const int *stop)
{
    hal_time_us_t until = rig_now_us(&cr->rig) + us;
    return rig_run_until(&cr->rig, until, stop);
}

/* The idle before a request: TSYN (and the link's idle) after the last frame on the line. */
static int wait_idle(cf_rig_t *cr)
{
    uint64_t now = rig_elapsed_ns(&cr->rig);
    uint64_t free_at = cr->line_free_ns + (uint64_t)cr->cfg.idle_us * 1000u;
    if (free_at <= now) {
        return 0;
    }
    uint32_t us = (uint32_t)((free_at - now + 999u) / 1000u);
    return run_for_us(cr, us, NULL);
}

static void take_reply(cf_rig_t *cr, cf_reply_t *out)
{
    memset(out, 0, sizeof *out);
    out->tsdr_bits = CF_TSDR_UNKNOWN;
    out->tx_t_ns = cr->tx_seen ? cr->tx_start_ns : rig_elapsed_ns(&cr->rig);
    size_t n = cr->rx_len > CF_FRAME_MAX ? CF_FRAME_MAX : cr->rx_len;
    memcpy(out->octets, cr->rx, n);
    out->len = (uint16_t)n;
    /* cppcheck 2.10 misses that the receive callback fills rx during the exchange. */
    // cppcheck-suppress knownConditionTrueFalse
    if (n == 0u) {
        return;
    }
    size_t want = telegram_len(cr->rx, cr->rx_len);
    out->garbled = cr->rx_overflow || want == SIZE_MAX || want != cr->rx_len ||
                   fdl_check(out->octets, n, NULL, NULL) != FDL_CHECK_OK;
    out->t_ns = cr->rx_seen ? cr->rx_start_ns : rig_elapsed_ns(&cr->rig);
    if (!wall(cr) && cr->tx_seen && cr->rx_seen) {
        /* TSDR: from the request's last stop bit to the answer's first start bit. */
        uint64_t tx_end = cr->tx_start_ns + (uint64_t)cr->tx_len * hal_uart_char_ns(cr->baud);
        if (cr->rx_start_ns >= tx_end) {
            uint64_t ns = cr->rx_start_ns - tx_end;
            /* whole bit times, rounded down: an answer a fraction of a bit early is early */
            out->tsdr_bits = (int32_t)((ns * cr->baud) / 1000000000u);
        }
    }
}

static int link_exchange(void *ctx, const uint8_t *octets, size_t len, uint32_t wait_us,
                         cf_reply_t *out)
{
    cf_rig_t *cr = ctx;
    if (wait_idle(cr) != 0) {
        return -1;
    }
    cr->rx_len = 0;
    cr->rx_overflow = false;
    cr->done = 0;
    cr->tx_seen = cr->rx_seen = false;
    cr->tx_len = len;
    cr->listening = true;
    if (cr->uart.ops->transmit(cr->uart.ctx, octets, len, rig_now_us(&cr->rig)) != 0) {
        cr->listening = false;
        snprintf(cr->err, sizeof cr->err, "the medium refused to transmit");
        return -1;
    }
    uint32_t tx_us = hal_uart_bits_us(cr->baud, (uint32_t)(len * HAL_UART_CHAR_BITS));
    /* Wall clock: write() returns before the characters are on the line, and a PTY or adapter
     * hands them over in batches: wait the whole slot for the first character. */
    int rc = run_for_us(cr, tx_us + wait_us, &cr->done);
    /* An answer begun within the slot time is heard to its end: the characters its delimiter
     * and length still promise, and a few more for garbage, as long as characters keep coming. */
    size_t heard = 0;
    while (rc == 0 && cr->rx_len > heard && cr->done == 0 && !cr->rx_overflow) {
        heard = cr->rx_len;
        size_t want = telegram_len(cr->rx, cr->rx_len);
        size_t more = want != SIZE_MAX && want > cr->rx_len ? want - cr->rx_len : 0u;
        uint32_t chars = (uint32_t)(GARBLE_QUIET_CHARS + more);
        uint32_t us = hal_uart_bits_us(cr->baud, chars * HAL_UART_CHAR_BITS) + 1u;
        rc = run_for_us(cr, wall(cr) && us < WALL_QUIET_US ? WALL_QUIET_US : us, &cr->done);
    }
    if (rc == 0 && !wall(cr) && cr->done != 0) {
        /* Let the answer's last character end before the next request is timed. */
        rc = run_for_us(cr, 1u, NULL);
    }
    cr->listening = false;
    take_reply(cr, out);
    return rc;
}

static int link_pause(void *ctx, uint32_t us)
{
    cf_rig_t *cr = ctx;
    return run_for_us(cr, us, NULL);
}

static int link_settle(void *ctx, uint32_t quiet_us, uint32_t max_us)
{
    cf_rig_t *cr = ctx;
    uint64_t until = rig_elapsed_ns(&cr->rig) + (uint64_t)max_us * 1000u;
    for (;;) {
        uint32_t heard = cr->rx_chars;
        if (run_for_us(cr, quiet_us, NULL) != 0) {
            return -1;
        }
        if (cr->rx_chars == heard || rig_elapsed_ns(&cr->rig) >= until) {
            return 0;
        }
    }
}

static int link_set_baud(void *ctx, uint32_t baud)
{
    cf_rig_t *cr = ctx;
    if (wall(cr) && cr->cfg.medium == RIG_MEDIUM_LCM) {
        return -1;
    }
    if (cr->uart.ops->set_baud(cr->uart.ctx, baud) != 0) {
        return -1;
    }
    cr->baud = baud;
    return 0;
}

static int link_power_cycle(void *ctx)
{
    cf_rig_t *cr = ctx;
    if (cr->card == NULL) {
        return -1;
    }
    rig_card_power_cycle(cr->card, rig_now_us(&cr->rig));
    return 0;
}

static const cf_link_ops_t rig_link_ops = {.exchange = link_exchange,
                                           .pause = link_pause,
                                           .set_baud = link_set_baud,
                                           .now_ns = link_now_ns,
                                           .power_cycle = link_power_cycle,
                                           .settle = link_settle};

/* Only the card in process can be switched off and on. */
static const cf_link_ops_t rig_link_ops_no_card = {.exchange = link_exchange,
                                                   .pause = link_pause,
                                                   .set_baud = link_set_baud,
                                                   .now_ns = link_now_ns,
                                                   .power_cycle = NULL,
                                                   .settle = link_settle};

static bool is_pty(const cf_rig_cfg_t *cfg)
{
    struct stat st;
    if (cfg->medium != RIG_MEDIUM_TTY) {
        return false;
    }
    if (cfg->use_fd) {
        return true; /* only a PTY's master side has no path */
    }
    if (stat(cfg->device, &st) != 0 || !S_ISCHR(st.st_mode)) {
        return true; /* not a device: nothing with a rate */
    }
    unsigned maj = major(st.st_rdev);
    return maj >= PTY_MAJOR_FIRST && maj <= PTY_MAJOR_LAST;
}

cf_link_t cf_rig_link(cf_rig_t *cr, const char *name)
{
    cf_link_t l = {.ops = &rig_link_ops, .ctx = cr, .name = name, .baud = cr->baud};
    l.timing = !wall(cr);
    l.has_baud = !wall(cr) || (cr->cfg.medium == RIG_MEDIUM_TTY && !is_pty(&cr->cfg));
    l.slot_us = cr->cfg.slot_us;
    /* Simulated time is exact: an unanswered request stays unanswered. A wall-clock medium
     * (a loaded host, QEMU) may answer late. */
    l.retries = wall(cr) ? CF_RIG_WALL_RETRIES : 0u;
    l.idle_us = cr->cfg.idle_us;
    if (cr->card == NULL) {
        l.ops = &rig_link_ops_no_card;
    }
    return l;
}

/* ---- opening ------------------------------------------------------------------------------ */

static void default_times(cf_rig_cfg_t *c)
{
    fdl_bus_params_t p;
    fdl_bus_params_default(&p, c->baud,
                           c->medium == RIG_MEDIUM_MEMBUS ? FDL_BUS_PROFILE_DP
                                                          : FDL_BUS_PROFILE_USB);
    if (c->slot_us == 0u) {
        c->slot_us = fdl_bus_us(&p, p.tsl_bits);
    }
    if (c->idle_us == 0u) {
        c->idle_us = fdl_bus_us(&p, fdl_bus_tid1_bits(&p));
        if (c->medium != RIG_MEDIUM_MEMBUS && c->idle_us < 2000u) {
            /* A PTY or adapter batches characters: keep requests apart by more than a batch. */
            c->idle_us = 2000u;
        }
    }
}

int cf_rig_open(cf_rig_t *cr, const cf_rig_cfg_t *cfg, char *err, size_t errlen)
{
    memset(cr, 0, sizeof *cr);
    cr->cfg = *cfg;
    cr->baud = cfg->baud;
    default_times(&cr->cfg);
    rig_cfg_t rc = {.medium = cfg->medium, .device = cfg->device, .use_fd = cfg->use_fd,
                    .fd = cfg->fd, .lcm_channel = cfg->lcm_channel, .lcm_url = cfg->lcm_url,
                    .lcm_station_address = -1, .lcm_key = cfg->lcm_key, .baud = cfg->baud,
                    .echo_suppress = cfg->echo_suppress, .start_ns = cfg->start_ns,
                    .every_telegram_to_cards = true};
    rig_init(&cr->rig, &rc);
    rig_tap_t tap = {.ctx = cr, .frame = tester_tap};
    (void)rig_add_tap(&cr->rig, &tap);
    if (rig_open(&cr->rig, err, errlen) != 0) {
        return -1;
    }
    if (cfg->medium == RIG_MEDIUM_MEMBUS) {
        card_options_t co = {.address = cfg->card_address, .strict_timing = true,
                             .inverter = CARD_INVERTER_NONE};
        cr->card = rig_add_card(&cr->rig, &co, rig_now_us(&cr->rig));
        if (cr->card == NULL) {
            snprintf(err, errlen, "the card could not be placed on the bus");
            rig_close(&cr->rig);
            return -1;
        }
    }
    sim_station_t st = {.ctx = cr, .rx_char = tester_rx, .poll = tester_poll};
    if (rig_attach_tester(&cr->rig, &st, &cr->uart) != 0) {
        snprintf(err, errlen, "the tester could not join the medium");
        rig_close(&cr->rig);
        return -1;
    }
    if (cr->uart.ops->set_baud(cr->uart.ctx, cfg->baud) != 0 && cfg->medium != RIG_MEDIUM_LCM) {
        snprintf(err, errlen, "the medium does not take %u bit/s", (unsigned)cfg->baud);
        rig_close(&cr->rig);
        return -1;
    }
    return 0;
}

void cf_rig_close(cf_rig_t *cr)
{
    rig_close(&cr->rig);
}
