/* The rig of slave and master with its taps. See session.h. */
#include "session.h"

#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "lcm_bridge/lcm_segment.h"

static bool open_capture(report_t *rep, const capture_opts_t *capture)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts);
    rep->capture_direction = true;
    return report_open_capture(rep, capture,
                               (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec);
}

/* Telegrams go to the capture, or through the LCM telemetry, which writes the capture first. */
static void session_frame(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                          uint32_t baud)
{
    session_t *s = ctx;
    if (s->telemetry.open) {
        lcm_cli_tap(&s->telemetry, t_ns, frame, len, local, baud);
    } else {
        report_tap(&s->rep, t_ns, frame, len, local, baud);
    }
}

static void session_param(void *ctx, unsigned card, uint8_t channel,
                          const uint8_t req[ML_TELEGRAM_LEN], const uint8_t rsp[ML_TELEGRAM_LEN])
{
    session_t *s = ctx;
    (void)card;
    if (s->telemetry.open) {
        dfp_lcm_bridge_param_observer(&s->telemetry.bridge, channel, req, rsp);
    }
}

static uint64_t session_now_ns(void *ctx)
{
    const session_t *s = ctx;
    return rig_elapsed_ns(&s->rig);
}

void session_close(session_t *s)
{
    instrument_stop(&s->in);
    rig_close(&s->rig);
}

int session_end(session_t *s, int rc)
{
    lcm_cli_close(&s->telemetry);
    session_close(s);
    return report_close_capture(&s->rep) != 0 ? 1 : rc;
}

/* A keyed segment's drops and totals, among the command's other lines. */
static void session_segment_log(void *ctx, const char *line)
{
    report_line(ctx, "lcm", "%s", line);
}

bool session_open(session_t *s, const medium_opts_t *m, int16_t station_address, uint32_t baud,
                  const capture_opts_t *capture, const instrument_opts_t *io, bool echo)
{
    char err[320];
    rig_cfg_t rc = {.medium = m->bus != NULL ? RIG_MEDIUM_LCM : RIG_MEDIUM_TTY,
                    .device = m->dev,
                    .use_fd = m->use_fd,
                    .fd = m->fd,
                    .lcm_channel = m->bus != NULL ? dfp_lcm_segment_channel(m->bus) : NULL,
                    .lcm_url = m->lcm_url,
                    .lcm_station_address = station_address,
                    .lcm_key = medium_key(m),
                    .baud = baud,
                    .echo_suppress = echo};
    rig_init(&s->rig, &rc);
    instrument_attach_log(&s->in, &s->rig, io);
    rig_tap_t taps = {.ctx = s, .frame = session_frame, .param = session_param};
    (void)rig_add_tap(&s->rig, &taps);
    if (rig_open(&s->rig, err, sizeof err) != 0) {
        cli_error("%s", err);
        if (m->use_fd) {
            (void)close(m->fd); /* a port that failed to open leaves it with us */
        }
        return false;
    }
    if (m->bus != NULL) {
        dfp_lcm_segment_set_log(&s->rig.segment, session_segment_log, &s->rep);
    }
    s->rep.now_ns = session_now_ns;
    s->rep.now_ctx = s;
    if (!open_capture(&s->rep, capture)) {
        session_close(s);
        return false;
    }
    cli_catch_stop_signals();
    return true;
}

int session_telemetry(session_t *s, const char *url, const dfp21b_t *card, uint8_t address)
{
    int64_t wall = lcm_cli_wall_of_mono(s->rig.cfg.medium == RIG_MEDIUM_LCM
                                            ? s->rig.segment.t0_ns
                                            : s->rig.runner->t0_ns);
    if (lcm_cli_open(&s->telemetry, url, card, address, &s->rep, wall, wall) != 0) {
        return -1;
    }
    (void)rig_add_timer(&s->rig, lcm_cli_timer, &s->telemetry);
    s->in.api_event = lcm_cli_api_event;
    s->in.api_event_ctx = &s->telemetry;
    return 0;
}

const char *session_medium_name(const session_t *s, const medium_opts_t *m, char *buf, size_t n)
{
    return medium_name(m, s->rig.segment.url, buf, n);
}
