/* dfp-sim monitor on a live source (mon_cmd.h): the session's medium (a tty, a PTY, an LCM
 * segment) with the monitor's listening station as its one station, the full-screen view or
 * event lines, and with --http the control API whose bus page shows this monitor. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "mon_cmd.h"
#include "report.h"
#include "sim_hal/tty_port.h"

#define MON_CMD_TICK_MS 250u

static void keys_readable(void *ctx, hal_time_us_t now)
{
    (void)now;
    mon_cmd_t *c = ctx;
    int key;
    bool changed = false;
    while ((key = mon_term_poll_key(&c->term)) >= 0) {
        mon_view_result_t r = mon_view_key(&c->view, key);
        if (r == MON_VIEW_QUIT) {
            cli_stop = 1;
            return;
        }
        changed = changed || r == MON_VIEW_CHANGED;
    }
    if (changed) {
        mon_term_draw(&c->term, c->mon, &c->view, c->now_ns);
    }
}

/* The full-screen view: keys come through the loop like the line's characters. False after
 * saying why (not a terminal). */
static bool open_top(mon_cmd_t *c)
{
    char err[200];
    if (mon_term_open(&c->term, 0, 1, err, sizeof err) != 0) {
        fprintf(stderr, "monitor: --view top: %s (--view log prints one line per event)\n", err);
        return false;
    }
    c->view.source = c->source;
    c->view.baud = c->o->baud;
    if (rig_add_fd(&c->session.rig, 0, keys_readable, c) != 0) {
        mon_term_close(&c->term);
        fprintf(stderr, "monitor: --view top: the loop has no room for the keyboard\n");
        return false;
    }
    c->top = true;
    return true;
}

static void tick(void *ctx, uint64_t now_ns)
{
    mon_cmd_t *c = ctx;
    c->now_ns = now_ns;
    if (c->top) {
        mon_term_draw(&c->term, c->mon, &c->view, now_ns);
    }
    if (c->api != NULL) {
        mon_rig_service(c->api, now_ns);
    }
    mon_cmd_pcapng_tick(c, now_ns);
}

/* --http: the API's monitor replaces the command's own, with its events and frames going
 * through the command first (the event lines, the pcapng record). */
static int start_api(mon_cmd_t *c)
{
    c->session.in.no_bus_monitor = true;
    int rc = instrument_start_http(&c->session.in, &c->session.rig, &c->o->io, "monitor", true);
    if (rc != 0 || !c->session.in.ctl_on) {
        return rc;
    }
    c->api = malloc(sizeof *c->api);
    if (c->api == NULL) {
        fprintf(stderr, "monitor: no memory for the API's bus monitor\n");
        return 1;
    }
    mon_rig_init(c->api, &c->session.in.ctl, &c->own.cfg, c->source, 0u);
    mon_t *m = &c->api->mon;
    c->api_event = m->cfg.on_event;
    c->api_ctx = m->cfg.ctx;
    m->cfg.on_event = mon_cmd_event;
    m->cfg.on_frame = mon_cmd_frame;
    m->cfg.ctx = c;
    c->mon = m;
    mon_rig_publish(c->api, 0u);
    return 0;
}

/* Until the end of the run: 0, or 1 with the reason in why (told by the caller once the
 * terminal is back: written on the alternate screen, it would vanish with it). */
static int run(mon_cmd_t *c, char *why, size_t n)
{
    const mon_cmd_opts_t *o = c->o;
    uint64_t limit_us = (uint64_t)o->seconds * 1000000u;
    /* Summed slice by slice: the 32-bit clock wraps every 71 minutes; --seconds goes to a
     * year. */
    hal_time_us_t before = tty_now_us();
    uint64_t spent_us = 0;
    while (cli_stop == 0 && (o->seconds == 0u || spent_us < limit_us)) {
        uint64_t left = o->seconds == 0u ? 200000u : limit_us - spent_us;
        uint32_t slice = (uint32_t)(left < 200000u ? left : 200000u);
        if (rig_run_until(&c->session.rig, tty_now_us() + slice, &cli_stop) < 0) {
            (void)snprintf(why, n, "%s", tty_runner_error(c->session.rig.runner));
            return 1;
        }
        hal_time_us_t now = tty_now_us();
        spent_us += (uint32_t)(now - before);
        before = now;
    }
    return 0;
}

/* An LCM segment hands a telegram sent at another rate on as framing errors, as a line does to
 * a receiver at the wrong rate: without this line a live list that stays empty says nothing of
 * why. */
static void tell_other_rate(const mon_cmd_t *c)
{
    const rig_t *r = &c->session.rig;
    uint64_t other = r->segment.frames_other_baud;
    if (r->cfg.medium != RIG_MEDIUM_LCM || other == 0u) {
        return;
    }
    char how_many[80] = "every telegram heard was";
    if (other != r->segment.frames_received) {
        (void)snprintf(how_many, sizeof how_many, "%llu of %llu telegrams heard were",
                       (unsigned long long)other,
                       (unsigned long long)r->segment.frames_received);
    }
    fprintf(stderr, "monitor: segment %s: %s sent at a rate other than --baud %s (heard "
            "garbled): give the segment's rate\n", r->cfg.lcm_channel, how_many,
            report_baud_text(c->o->baud));
}

int mon_cmd_live(mon_cmd_t *c)
{
    const mon_cmd_opts_t *o = c->o;
    capture_opts_t no_capture;
    memset(&no_capture, 0, sizeof no_capture);
    if (!session_open(&c->session, &o->med, -1, o->baud, &no_capture, &o->io, false)) {
        return 1;
    }
    int rc = start_api(c);
    if (rc != 0) {
        session_close(&c->session);
        return rc;
    }
    mon_live_init(&c->live, c->mon, o->baud);
    c->live.tick = tick;
    c->live.tick_ctx = c;
    c->live.tick_ms = MON_CMD_TICK_MS;
    sim_station_t st = mon_live_station(&c->live);
    if (rig_attach_listener(&c->session.rig, &st) != 0) {
        fprintf(stderr, "monitor: cannot listen on %s\n", c->source);
        session_close(&c->session);
        return 1;
    }
    if (o->view == MON_VIEW_TOP && !open_top(c)) {
        session_close(&c->session);
        return EXIT_USAGE;
    }
    char why[300] = "";
    rc = run(c, why, sizeof why);
    if (c->top) {
        (void)tty_runner_remove_fd(c->session.rig.runner, 0);
        mon_term_close(&c->term);
        c->top = false;
    }
    if (rc != 0) {
        fprintf(stderr, "monitor: %s\n", why);
    }
    tell_other_rate(c);
    session_close(&c->session);
    return rc;
}
