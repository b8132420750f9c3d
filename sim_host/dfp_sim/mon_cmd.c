/* dfp-sim monitor's run (mon_cmd.h). */
#include "mon_cmd.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "lcm_bridge/lcm_segment.h"

#define NS_PER_S 1000000000ull

static const char *level_word(mon_level_t l)
{
    return l == MON_LEVEL_ERROR ? "error" : l == MON_LEVEL_WARN ? "warn" : "info";
}

static void on_event(void *ctx, const mon_event_t *ev)
{
    mon_cmd_t *c = ctx;
    if (c->o->view == MON_VIEW_LOG) {
        printf("%11.6f %-5s %s\n", (double)ev->t_ns / 1e9, level_word(ev->level), ev->text);
        fflush(stdout);
    }
}

static uint64_t wall_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint64_t)ts.tv_sec * NS_PER_S + (uint64_t)ts.tv_nsec;
}

static void pcapng_told(mon_cmd_t *c)
{
    const char *why = pcapng_writer_error(&c->pcapng);
    if (why != NULL) {
        fprintf(stderr, "monitor: %s; the monitor goes on without it\n", why);
    }
}

static void on_frame(void *ctx, const uint8_t *f, size_t len, uint64_t t_ns, bool garbled)
{
    mon_cmd_t *c = ctx;
    if (!c->recording) {
        return;
    }
    int rc = garbled ? pcapng_writer_garbled(&c->pcapng, t_ns, f, len)
                     : pcapng_writer_telegram(&c->pcapng, t_ns, f, len);
    if (rc != 0) {
        pcapng_told(c);
    }
}

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
        mon_term_draw(&c->term, &c->mon, &c->view, c->now_ns);
    }
}

/* The full-screen view, when asked for: keys come through the loop like the line's
 * characters. False after saying why (not a terminal). */
static bool open_top(mon_cmd_t *c)
{
    char err[200];
    if (mon_term_open(&c->term, 0, 1, err, sizeof err) != 0) {
        fprintf(stderr, "monitor: --view top: %s (--view log prints one line per event)\n", err);
        return false;
    }
    c->view.source = c->source;
    c->view.baud = c->o->baud;
    if (tty_runner_add_fd(&c->live.runner, 0, keys_readable, c) != 0) {
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
        mon_term_draw(&c->term, &c->mon, &c->view, now_ns);
    }
    if (c->recording && pcapng_writer_tick(&c->pcapng, now_ns) != 0) {
        pcapng_told(c);
    }
}

static bool open_pcapng(mon_cmd_t *c, const char *source)
{
    if (c->o->pcapng == NULL) {
        return true;
    }
    char desc[64];
    (void)snprintf(desc, sizeof desc, "PROFIBUS at %u bit/s, heard by dfp-sim monitor",
                   c->o->baud);
    pcapng_writer_opt_t opt = {.baud = c->o->baud, .if_name = source, .if_description = desc,
                               .base_ns = wall_ns()};
    char err[700];
    if (pcapng_writer_open(&c->pcapng, c->o->pcapng, &opt, err, sizeof err) != 0) {
        fprintf(stderr, "monitor: %s\n", err);
        return false;
    }
    c->recording = true;
    return true;
}

static int open_source(mon_cmd_t *c)
{
    const mon_cmd_opts_t *o = c->o;
    char err[300];
    int rc;
    if (o->med.dev != NULL) {
        rc = mon_live_open_port(&c->live, &c->mon, o->med.dev, o->baud, err, sizeof err);
        (void)snprintf(c->source, sizeof c->source, "%s", o->med.dev);
    } else {
        const char *channel = dfp_lcm_segment_channel(o->med.bus);
        rc = mon_live_open_lcm(&c->live, &c->mon, o->med.lcm_url, channel, medium_key(&o->med),
                               o->baud, err, sizeof err);
        (void)snprintf(c->source, sizeof c->source, "LCM segment %s", channel);
    }
    if (rc != 0) {
        fprintf(stderr, "monitor: %s\n", err);
        mon_live_close(&c->live);
        return 1;
    }
    return 0;
}

static void summary(const mon_cmd_t *c)
{
    const mon_line_t *l = &c->mon.line;
    printf("monitor: %s: %llu telegrams, %llu garbled, %llu unanswered, %llu events\n",
           c->source, (unsigned long long)l->telegrams, (unsigned long long)l->garbled,
           (unsigned long long)l->unanswered, (unsigned long long)c->mon.events_total);
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        const mon_station_t *s = &c->mon.st[a];
        if (!s->seen) {
            continue;
        }
        printf("  %3u %-7s %-9s", a, mon_role_name(s->role),
               s->dp ? mon_dp_state_name(s->dp_state) : (s->in_ring ? "in ring" : "-"));
        if (s->dp && s->master != MON_NO_MASTER) {
            printf(" master %u", s->master);
        }
        if (s->ident_known) {
            printf(" ident 0x%04X", s->ident);
        }
        printf("\n");
    }
}

int mon_cmd_run(mon_cmd_t *c, const mon_cmd_opts_t *o)
{
    memset(c, 0, sizeof *c);
    c->o = o;
    mon_cfg_t cfg = {.baud = o->baud, .timing = o->timing, .tsl_bits = o->tsl_bits,
                     .ttr_bits = o->ttr_bits, .on_event = on_event, .on_frame = on_frame,
                     .ctx = c};
    mon_init(&c->mon, &cfg);
    int rc = 0;
    if (!open_pcapng(c, o->file != NULL ? o->file : (o->med.dev != NULL ? o->med.dev : o->med.bus))) {
        return EXIT_USAGE;
    }
    if (o->file != NULL) {
        (void)snprintf(c->source, sizeof c->source, "%s", o->file);
        char err[1100];
        if (mon_file_run(&c->mon, o->file, o->baud, &cli_stop, err, sizeof err) < 0) {
            fprintf(stderr, "monitor: %s\n", err);
            rc = 1;
        }
    } else {
        c->live.tick = tick;
        c->live.tick_ctx = c;
        c->live.tick_ms = 250u;
        if (open_source(c) != 0) {
            if (c->recording) {
                (void)pcapng_writer_close(&c->pcapng);
            }
            return 1;
        }
        if (o->view == MON_VIEW_TOP && !open_top(c)) {
            mon_live_close(&c->live);
            if (c->recording) {
                (void)pcapng_writer_close(&c->pcapng);
            }
            return EXIT_USAGE;
        }
        cli_catch_stop_signals();
        char err[300];
        if (mon_live_run(&c->live, o->seconds, &cli_stop, err, sizeof err) != 0) {
            fprintf(stderr, "monitor: %s\n", err);
            rc = 1;
        }
        if (c->top) {
            (void)tty_runner_remove_fd(&c->live.runner, 0);
            mon_term_close(&c->term);
            c->top = false;
        }
        mon_live_close(&c->live);
    }
    summary(c);
    if (c->recording && pcapng_writer_close(&c->pcapng) != 0) {
        pcapng_told(c);
        rc = 1;
    }
    return rc;
}
