#include "instrument.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#define PUBLISH_EVERY_NS 20000000u /* the snapshot clients read is at most 20 ms old */

void instrument_defaults(instrument_opts_t *o, rig_log_time_t time)
{
    memset(o, 0, sizeof *o);
    o->level = RIG_LOG_INFO;
    o->time = time;
}

#define WEB(field) offsetof(instrument_http_opts_t, field)
#define GIVEN CLI_SEEN(instrument_http_opts_t, given)

const cli_opt_t instrument_http_options[7] = {
    {CLI_OPT("--http-token-file", "FILE", CLI_TEXT, WEB(token_file)), .seen = GIVEN},
    {CLI_OPT("--http-viewer-token-file", "FILE", CLI_TEXT, WEB(viewer_token_file)),
     .seen = GIVEN},
    {CLI_OPT("--http-no-auth", NULL, CLI_FLAG, WEB(no_auth)), .seen = GIVEN},
    {CLI_OPT("--http-allow-host", "NAME", CLI_LIST, WEB(allow_host)), .aux = WEB(n_allow_host),
     .max = HTTP_MAX_ALLOWED, .seen = GIVEN},
    {CLI_OPT("--http-allow-origin", "ORIGIN", CLI_LIST, WEB(allow_origin)),
     .aux = WEB(n_allow_origin),
     .max = HTTP_MAX_ALLOWED, .seen = GIVEN},
    {CLI_OPT("--http-cert", "FILE", CLI_TEXT, WEB(cert)), .seen = GIVEN},
    {CLI_OPT("--http-key", "FILE", CLI_TEXT, WEB(key)), .seen = GIVEN},
};

static bool set_quiet(void *base, const cli_opt_t *opt, const char *value, cli_args_t *args)
{
    (void)opt;
    (void)value;
    (void)args;
    ((instrument_opts_t *)base)->level = RIG_LOG_WARN;
    return true;
}

static const cli_choice_t log_levels[] = {
    {"error", RIG_LOG_ERROR, false},
    {"warn", RIG_LOG_WARN, false},
    {"info", RIG_LOG_INFO, false},
    {"debug", RIG_LOG_DEBUG, false},
    {NULL, 0, false},
};

static const cli_choice_t log_times[] = {
    {"bus", RIG_LOG_TIME_BUS, false},
    {"wall", RIG_LOG_TIME_WALL, false},
    {NULL, 0, false},
};

const cli_opt_t instrument_options[4] = {
    {CLI_OPT("--http", "[ADDR:]PORT", CLI_TEXT, offsetof(instrument_opts_t, http))},
    {CLI_OPT("--quiet", NULL, CLI_CALL, 0), .set = set_quiet},
    {CLI_OPT("--log-level", "error|warn|info|debug", CLI_CHOICE,
            offsetof(instrument_opts_t, level)),
     .choices = log_levels, .bad = "--log-level: '%s' is not one of error, warn, info, debug"},
    {CLI_OPT("--timestamps", "bus|wall", CLI_CHOICE, offsetof(instrument_opts_t, time)),
     .choices = log_times, .bad = "--timestamps: '%s' is not wall or bus"},
};

void instrument_attach_log(instrument_t *in, rig_t *r, const instrument_opts_t *o)
{
    memset(in, 0, sizeof *in);
    rig_log_init(&in->log, r, stdout);
    in->log.level = o->level;
    in->log.time = o->time;
    rig_tap_t tap = rig_log_tap(&in->log);
    rig_add_tap(r, &tap);
}

/* Wall-clock loops: actions wake the loop through the bridge's descriptor; the snapshot still
 * needs a turn of its own when the bus is quiet. */
static hal_time_us_t service_timer(void *ctx, hal_time_us_t now)
{
    instrument_service(ctx);
    return now + PUBLISH_EVERY_NS / 1000u;
}

/* ---- the control API's credentials and TLS (docs/api.md "Security") ---- */

static void http_config_from(const instrument_opts_t *o, const http_credentials_t *k,
                             http_config_t *c)
{
    const instrument_http_opts_t *w = &o->web;
    memset(c, 0, sizeof *c);
    c->listen = o->http;
    c->no_auth = w->no_auth;
    c->token = w->no_auth ? NULL : k->token;
    c->viewer_token = k->viewer[0] != '\0' ? k->viewer : NULL;
    memcpy(c->allow_host, w->allow_host, sizeof c->allow_host);
    c->n_allow_host = w->n_allow_host;
    memcpy(c->allow_origin, w->allow_origin, sizeof c->allow_origin);
    c->n_allow_origin = w->n_allow_origin;
    c->cert_pem = k->cert_pem;
    c->key_pem = k->key_pem;
}

/* Like Jupyter: the URL to open, with the token, once on stderr (never into the rig's log,
 * which the API serves). */
static void print_urls(const instrument_opts_t *o, const char *host, uint16_t port,
                       const http_credentials_t *k, bool read_only)
{
    bool tls = o->web.cert != NULL;
    /* A wildcard address is reached through loopback from this machine. */
    const char *shown = strcmp(host, "0.0.0.0") == 0 ? "127.0.0.1"
                        : strcmp(host, "::") == 0    ? "::1"
                                                     : host;
    bool v6 = strchr(shown, ':') != NULL;
    char base[128];
    snprintf(base, sizeof base, "%s://%s%s%s:%u/", tls ? "https" : "http", v6 ? "[" : "",
             shown, v6 ? "]" : "", port);
    if (o->web.no_auth) {
        fprintf(stderr, "dfp-sim: control panel at %s%s\n", base,
                read_only ? " (read-only)" : "");
    } else {
        fprintf(stderr, "dfp-sim: control panel at %s?token=%s%s\n", base, k->token,
                read_only ? " (read-only)" : "");
    }
    if (k->viewer[0] != '\0') {
        fprintf(stderr, "dfp-sim: read-only panel at %s?token=%s\n", base, k->viewer);
    }
    if (!http_is_loopback(host) && !tls) {
        fprintf(stderr, "dfp-sim: warning: --http %s without --http-cert: the token crosses "
                "the network in clear text\n", o->http);
    }
    (void)fflush(stderr);
}

/* ---- the bus monitor (GET /api/v1/bus, the panel's bus page) ---- */

static const char *medium_name(const rig_t *r, char *buf, size_t n)
{
    switch (r->cfg.medium) {
    case RIG_MEDIUM_MEMBUS:
        return "in-memory bus";
    case RIG_MEDIUM_TTY:
        return r->cfg.device != NULL ? r->cfg.device : "tty";
    case RIG_MEDIUM_LCM:
        snprintf(buf, n, "LCM segment %s", r->cfg.lcm_channel);
        return buf;
    }
    return "";
}

/* Without a monitor the API answers GET /api/v1/bus with 404 and the rest works as before. */
static void attach_monitor(instrument_t *in, rig_t *r)
{
    mon_rig_t *l = malloc(sizeof *l);
    if (l == NULL) {
        rig_log(&in->log, RIG_LOG_WARN, "sim", "action", "no memory for the bus monitor: "
                "GET /api/v1/bus answers 404");
        return;
    }
    /* Only the in-memory bus gives the line's own times; a PTY or USB adapter batches. */
    mon_cfg_t cfg = {.baud = r->has_master ? r->master.cfg.baud : r->cfg.baud,
                     .timing = r->cfg.medium == RIG_MEDIUM_MEMBUS};
    char buf[96];
    mon_rig_init(l, &in->ctl, &cfg, medium_name(r, buf, sizeof buf), rig_elapsed_ns(r));
    rig_tap_t tap = mon_rig_tap(l);
    if (rig_add_tap(r, &tap) != 0) {
        in->ctl.bus = NULL;
        free(l);
        rig_log(&in->log, RIG_LOG_WARN, "sim", "action", "no tap left for the bus monitor: "
                "GET /api/v1/bus answers 404");
        return;
    }
    in->mon = l;
    mon_rig_publish(l, rig_elapsed_ns(r));
}

/* Starts the server itself; 0, or EXIT_USAGE after reporting. */
static int http_begin(instrument_t *in, const instrument_opts_t *o, bool read_only)
{
    char host[64] = "127.0.0.1";
    char err[400];
    uint16_t port;
    if (!http_parse_listen(o->http, host, sizeof host, &port, err, sizeof err)) {
        cli_error("%s", err);
        return EXIT_USAGE;
    }
    const instrument_http_opts_t *w = &o->web;
    const http_credential_sources_t src = {.no_auth = w->no_auth,
                                           .token_file = w->token_file,
                                           .viewer_token_file = w->viewer_token_file,
                                           .cert = w->cert,
                                           .key = w->key};
    http_credentials_t k;
    http_config_t cfg;
    int rc = 0;
    if (!http_credentials_load(&src, host, &k, err, sizeof err)) {
        cli_error("%s", err);
        rc = EXIT_USAGE;
    } else {
        http_config_from(o, &k, &cfg);
        in->http = http_server_start(&in->ctl, &cfg, err, sizeof err);
        if (in->http == NULL) {
            cli_error("%s", err);
            rc = EXIT_USAGE;
        } else {
            print_urls(o, host, http_server_port(in->http), &k, read_only);
            bool v6 = strchr(host, ':') != NULL;
            rig_log(&in->log, RIG_LOG_INFO, "sim", "action", "control API and front panel on "
                    "%s://%s%s%s:%u/%s", o->web.cert != NULL ? "https" : "http", v6 ? "[" : "",
                    host, v6 ? "]" : "", http_server_port(in->http),
                    read_only ? " (read-only)" : "");
        }
    }
    http_credentials_free(&k);
    return rc;
}

int instrument_start_http(instrument_t *in, rig_t *r, const instrument_opts_t *o,
                          const char *mode, bool read_only)
{
    if (o->http == NULL) {
        if (o->web.given) {
            cli_error("the --http-* options need --http [ADDR:]PORT");
            return EXIT_USAGE;
        }
        return 0;
    }
    if (rig_ctl_init(&in->ctl, r, mode, read_only) != 0) {
        cli_error("--http: cannot set up the control bridge");
        return 1;
    }
    in->ctl_on = true;
    in->log.ctl = &in->ctl;
    in->api_seen = rig_ctl_next_seq(&in->ctl);
    if (rig_ctl_attach(&in->ctl) != 0) {
        cli_error("--http: the loop cannot wait on another descriptor");
        return 1;
    }
    if (!in->no_bus_monitor) {
        attach_monitor(in, r);
    }
    rig_add_timer(r, service_timer, in);
    rig_ctl_service(&in->ctl, 0);
    return http_begin(in, o, read_only);
}

/* The request threads publish the API's events to the bridge only: the terminal log and the
 * LCM telemetry belong to the loop's thread. At most INSTRUMENT_API_EVENTS_PER_TURN go on per
 * turn, so a client provoking refusals by the thousand costs the loop a bounded time; the rest
 * of a burst is counted in one line (GET /api/v1/log has them while the ring holds them). */
static void pass_on_api_events(instrument_t *in)
{
    unsigned passed = 0;
    uint64_t skipped = 0;
    for (;;) {
        uint64_t lost = 0;
        size_t n = rig_ctl_events(&in->ctl, in->api_seen, in->batch, INSTRUMENT_EVENT_BATCH,
                                  &lost);
        for (size_t i = 0; i < n; i++) {
            const rig_ctl_event_t *e = &in->batch[i];
            in->api_seen = e->seq + 1u;
            if (strcmp(e->source, "http") != 0) {
                continue;
            }
            if (passed == INSTRUMENT_API_EVENTS_PER_TURN) {
                skipped++;
                continue;
            }
            passed++;
            rig_log_print(&in->log, e->level, e->source, e->t_us, e->text);
            if (in->api_event != NULL) {
                in->api_event(in->api_event_ctx, e);
            }
        }
        if (n < INSTRUMENT_EVENT_BATCH) {
            break;
        }
    }
    if (skipped != 0u) {
        char text[RIG_CTL_TEXT];
        snprintf(text, sizeof text, "%llu more events of the API not shown here (over %u in "
                 "%u ms); GET /api/v1/log has them", (unsigned long long)skipped,
                 INSTRUMENT_API_EVENTS_PER_TURN, (unsigned)(PUBLISH_EVERY_NS / 1000000u));
        rig_log_print(&in->log, RIG_LOG_WARN, "http", rig_ctl_time_us(&in->ctl), text);
    }
}

void instrument_service(instrument_t *in)
{
    if (in->ctl_on) {
        if (in->mon != NULL) {
            mon_rig_service(in->mon, rig_elapsed_ns(in->ctl.rig));
        }
        rig_ctl_service(&in->ctl, PUBLISH_EVERY_NS);
        pass_on_api_events(in);
    }
}

void instrument_stop(instrument_t *in)
{
    if (in->http != NULL) {
        http_server_stop(in->http);
        in->http = NULL;
    }
    if (in->ctl_on) {
        in->log.ctl = NULL;
        rig_ctl_destroy(&in->ctl);
        in->ctl_on = false;
    }
}
