/* dfp-sim monitor's run (mon_cmd.h). */
#include "mon_cmd.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "gsd/gsd.h"
#include "monitor/mon_report.h"
#include "sim_hal/path.h"

#define NS_PER_S 1000000000ull

static const char *level_word(mon_level_t l)
{
    return l == MON_LEVEL_ERROR ? "error" : l == MON_LEVEL_WARN ? "warn" : "info";
}

/* The log's levels (rig_log_level_t: error 0, warn 1, info 2) for --quiet and --log-level. */
static int level_rank(mon_level_t l)
{
    return l == MON_LEVEL_ERROR ? 0 : l == MON_LEVEL_WARN ? 1 : 2;
}

void mon_cmd_event(void *ctx, const mon_event_t *ev)
{
    mon_cmd_t *c = ctx;
    if (c->o->view == MON_VIEW_LOG && level_rank(ev->level) <= (int)c->o->io.level) {
        printf("%11.6f %-5s %s\n", (double)ev->t_ns / 1e9, level_word(ev->level), ev->text);
        fflush(stdout);
    }
    if (c->api_event != NULL) {
        c->api_event(c->api_ctx, ev);
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

void mon_cmd_frame(void *ctx, const uint8_t *f, size_t len, uint64_t t_ns, bool garbled)
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

void mon_cmd_pcapng_tick(mon_cmd_t *c, uint64_t now_ns)
{
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

static void file_put(void *ctx, const char *text, size_t n)
{
    if (fwrite(text, 1, n, ctx) != n) {
        return; /* ferror() is looked at when the file is closed */
    }
}

static mon_report_info_t report_info(const mon_cmd_t *c)
{
    uint64_t now = c->o->file != NULL ? c->mon->line.last_ns : c->now_ns;
    mon_report_info_t info = {.source = c->source, .t_start_ns = 0u, .t_now_ns = now,
                              .last_events = 50u};
    return info;
}

/* The --report files; false after saying which could not be written. */
static bool write_reports(const mon_cmd_t *c, const mon_report_opts_t *ropt)
{
    mon_report_info_t info = report_info(c);
    bool ok = true;
    for (size_t k = 0; k < c->o->n_reports; k++) {
        const cli_kind_file_t *r = &c->o->reports[k];
        char why[300];
        FILE *f = sim_fopen_write(r->path, why, sizeof why);
        if (f == NULL) {
            fprintf(stderr, "monitor: cannot write %s: %s\n", r->path, why);
            ok = false;
            continue;
        }
        mon_sink_t out = {file_put, f};
        if (r->kind == MON_REPORT_JUNIT) {
            mon_report_junit(c->mon, &info, ropt, &out);
        } else {
            mon_report_json(c->mon, &info, &out);
        }
        bool bad = ferror(f) != 0;
        if (fclose(f) != 0 || bad) {
            fprintf(stderr, "monitor: cannot write %s: %s\n", r->path, strerror(errno));
            ok = false;
        }
    }
    return ok;
}

/* The summary, the reports and the exit status: 0 when every check passes, 1 otherwise. */
static int finish(const mon_cmd_t *c)
{
    const mon_cmd_opts_t *o = c->o;
    mon_report_opts_t ropt = {.max_repeats = o->max_repeats, .max_missing = o->max_missing,
                              .expect = o->expect, .n_expect = o->n_expect};
    mon_report_info_t info = report_info(c);
    mon_sink_t out = {file_put, stdout};
    mon_report_text(c->mon, &info, &out);
    fflush(stdout);
    bool written = write_reports(c, &ropt);
    return written && mon_report_ok(c->mon, &ropt) ? 0 : 1;
}

/* The --report files are written at the end: one that cannot be (a directory, no such
 * directory, no permission) is said at the start, not after a run of hours. */
static bool reports_writable(const mon_cmd_opts_t *o)
{
    for (size_t k = 0; k < o->n_reports; k++) {
        const char *path = o->reports[k].path;
        char dir[4096];
        const char *slash = strrchr(path, '/');
        size_t n = slash == NULL ? 1u : (slash == path ? 1u : (size_t)(slash - path));
        (void)snprintf(dir, sizeof dir, "%.*s", (int)n, slash == NULL ? "." : path);
        struct stat st;
        const char *why = NULL;
        if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
            why = "it is a directory";
        } else if (access(dir, W_OK) != 0) {
            why = strerror(errno);
        }
        if (why != NULL) {
            fprintf(stderr, "monitor: --report %s %s: cannot write it: %s\n",
                    o->reports[k].kind == MON_REPORT_JUNIT ? "junit" : "json", path, why);
            return false;
        }
    }
    return true;
}

/* --gsd FILE...: each file's ident and its MaxTsdr at the line's rate into cfg. False after
 * saying which file is unreadable or does not list the rate. */
static bool read_gsd(const mon_cmd_opts_t *o, mon_cfg_t *cfg)
{
    if (o->n_gsd == 0u) {
        return true;
    }
    gsd_t *g = malloc(sizeof *g); /* a quarter of a megabyte: not on the stack */
    if (g == NULL) {
        fprintf(stderr, "monitor: out of memory\n");
        return false;
    }
    bool ok = true;
    for (size_t k = 0; k < o->n_gsd && ok; k++) {
        char err[600];
        uint32_t ident = 0;
        if (gsd_parse_file(o->gsd[k], g, err, sizeof err) != 0) {
            fprintf(stderr, "monitor: --gsd %s\n", err);
            ok = false;
        } else if (!gsd_key(g, GSD_K_IDENT_NUMBER, &ident)) {
            fprintf(stderr, "monitor: --gsd %s: no Ident_Number\n", o->gsd[k]);
            ok = false;
        } else if (gsd_max_tsdr_bits(g, o->baud) == 0u) {
            fprintf(stderr, "monitor: --gsd %s: the slave does not support %u bit/s (no "
                    "MaxTsdr for it)\n", o->gsd[k], o->baud);
            ok = false;
        } else {
            cfg->gsd[cfg->n_gsd].ident = (uint16_t)ident;
            cfg->gsd[cfg->n_gsd].max_tsdr_bits = gsd_max_tsdr_bits(g, o->baud);
            cfg->n_gsd++;
        }
    }
    free(g);
    return ok;
}

int mon_cmd_run(mon_cmd_t *c, const mon_cmd_opts_t *o)
{
    memset(c, 0, sizeof *c);
    c->o = o;
    c->mon = &c->own;
    mon_cfg_t cfg = {.baud = o->baud, .timing = o->timing, .tsl_bits = o->tsl_bits,
                     .ttr_bits = o->ttr_bits, .on_event = mon_cmd_event,
                     .on_frame = mon_cmd_frame, .ctx = c};
    if (!read_gsd(o, &cfg) || !reports_writable(o)) {
        return EXIT_USAGE;
    }
    mon_init(&c->own, &cfg);
    const char *source = o->file != NULL ? o->file : (o->med.dev != NULL ? o->med.dev : o->med.bus);
    (void)snprintf(c->source, sizeof c->source, "%s", source);
    if (!open_pcapng(c, source)) {
        return EXIT_USAGE;
    }
    int rc = 0;
    if (o->file != NULL) {
        char err[1100];
        if (mon_file_run(c->mon, o->file, o->baud, &cli_stop, err, sizeof err) < 0) {
            fprintf(stderr, "monitor: %s\n", err);
            rc = 1;
        }
    } else {
        rc = mon_cmd_live(c);
        if (rc == EXIT_USAGE) {
            if (c->recording) {
                (void)pcapng_writer_close(&c->pcapng);
            }
            return rc;
        }
    }
    int checks = finish(c);
    rc = rc != 0 ? rc : checks;
    if (c->recording && pcapng_writer_close(&c->pcapng) != 0) {
        pcapng_told(c);
        rc = 1;
    }
    return rc;
}
