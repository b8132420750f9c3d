#include "instrument.h"

#include <stdio.h>
#include <string.h>

#include "cli.h"

#define PUBLISH_EVERY_NS 20000000u /* the snapshot clients read is at most 20 ms old */

void instrument_defaults(instrument_opts_t *o, rig_log_time_t time)
{
    memset(o, 0, sizeof *o);
    o->level = RIG_LOG_INFO;
    o->time = time;
}

int instrument_option(int argc, char **argv, int *i, instrument_opts_t *o)
{
    const char *opt = argv[*i];
    if (strcmp(opt, "--http") == 0) {
        return (o->http = cli_value(argc, argv, i)) != NULL ? 1 : -1;
    }
    if (strcmp(opt, "--quiet") == 0) {
        o->level = RIG_LOG_WARN;
        return 1;
    }
    if (strcmp(opt, "--log-level") == 0) {
        const char *v = cli_value(argc, argv, i);
        if (v == NULL) {
            return -1;
        }
        if (!rig_log_level_parse(v, &o->level)) {
            cli_error("--log-level: '%s' is not one of error, warn, info, debug", v);
            return -1;
        }
        return 1;
    }
    if (strcmp(opt, "--timestamps") == 0) {
        const char *v = cli_value(argc, argv, i);
        if (v == NULL) {
            return -1;
        }
        if (strcmp(v, "wall") == 0) {
            o->time = RIG_LOG_TIME_WALL;
        } else if (strcmp(v, "bus") == 0) {
            o->time = RIG_LOG_TIME_BUS;
        } else {
            cli_error("--timestamps: '%s' is not wall or bus", v);
            return -1;
        }
        return 1;
    }
    return 0;
}

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

int instrument_start_http(instrument_t *in, rig_t *r, const instrument_opts_t *o,
                          const char *mode, bool read_only)
{
    if (o->http == NULL) {
        return 0;
    }
    if (rig_ctl_init(&in->ctl, r, mode, read_only) != 0) {
        cli_error("--http: cannot set up the control bridge");
        return 1;
    }
    in->ctl_on = true;
    in->log.ctl = &in->ctl;
    if (rig_ctl_attach(&in->ctl) != 0) {
        cli_error("--http: the loop cannot wait on another descriptor");
        return 1;
    }
    rig_add_timer(r, service_timer, in);
    rig_ctl_service(&in->ctl, 0);
    char err[300];
    in->http = http_server_start(&in->ctl, o->http, err, sizeof err);
    if (in->http == NULL) {
        cli_error("%s", err);
        return EXIT_USAGE;
    }
    char host[64] = "127.0.0.1";
    uint16_t port;
    (void)http_parse_listen(o->http, host, sizeof host, &port, err, sizeof err);
    bool v6 = strchr(host, ':') != NULL;
    rig_log(&in->log, RIG_LOG_INFO, "sim", "action", "control API and front panel on "
            "http://%s%s%s:%u/%s", v6 ? "[" : "", host, v6 ? "]" : "",
            http_server_port(in->http), read_only ? " (read-only)" : "");
    return 0;
}

void instrument_service(instrument_t *in)
{
    if (in->ctl_on) {
        rig_ctl_service(&in->ctl, PUBLISH_EVERY_NS);
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
