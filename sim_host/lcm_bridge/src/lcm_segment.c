#include "lcm_bridge/lcm_segment.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <lcm/lcm.h>

#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "lcm_bridge/lcm_bridge.h"
#include "lcm_bridge/telegram_decode.h"
#include "sim_hal/host_clock.h"

/* One readable() call handles at most this many messages, so a flood cannot starve the
 * station's timers; the descriptor stays readable and the runner comes back. */
#define SEGMENT_HANDLE_BURST 256

/* More than this ahead is a clock mix-up, as on a tty. */
#define SEGMENT_MAX_TX_WAIT_US 10000000

const char *dfp_lcm_segment_channel(const char *text)
{
    if (text == NULL || strncmp(text, "lcm:", 4) != 0) {
        return NULL;
    }
    const char *ch = text + 4;
    size_t n = strlen(ch);
    if (n == 0u || n > 63u) {
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        char c = ch[i];
        bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                  c == '_' || c == '.' || c == '-';
        if (!ok) {
            return NULL;
        }
    }
    return ch;
}

static void on_telegram(dfp_lcm_segment_t *s, const dfp_lcm_telegram_t *msg)
{
    if (msg->source_id == s->source_id) {
        s->own_ignored++;
        return;
    }
    if (!s->station_attached || msg->length <= 0) {
        return;
    }
    s->frames_received++;
    uint64_t t_ns = host_clock_mono_ns();
    hal_time_us_t t = (hal_time_us_t)(t_ns / 1000u);
    uint8_t flags = (uint8_t)((uint16_t)msg->error_flags &
                              (HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR |
                               HAL_UART_RX_OVERRUN_ERR));
    bool other_baud = (uint32_t)msg->baud != s->baud;
    if (other_baud) {
        s->frames_other_baud++;
        flags |= HAL_UART_RX_FRAMING_ERR;
    }
    size_t len = (size_t)msg->length;
    /* Tapped before the station hears it: a card answers inside rx_char, and its reply must
     * not reach the log (LCM telemetry, captures) ahead of the request. */
    if (s->tap != NULL && flags == 0u) {
        s->tap(s->tap_ctx, t_ns - s->t0_ns, msg->data, len, false, s->baud);
    }
    for (size_t i = 0; i < len && s->station.rx_char != NULL; i++) {
        s->station.rx_char(s->station.ctx, msg->data[i], flags, t);
    }
}

static void segment_log(dfp_lcm_segment_t *s, const char *line)
{
    if (s->log != NULL) {
        s->log(s->log_ctx, line);
    } else {
        fprintf(stderr, "%s\n", line);
    }
}

static void log_thunk(void *ctx, const char *line)
{
    segment_log(ctx, line);
}

static int64_t mono_us(void)
{
    return (int64_t)(host_clock_mono_ns() / 1000u);
}

static void drop(dfp_lcm_segment_t *s, dfp_seg_drop_t why, const char *detail)
{
    dfp_seg_drops_add(&s->drops, why, s->channel, detail, mono_us(), log_thunk, s);
}

/* A plain telegram_t, or anything that is no signed_telegram_t. */
static void on_plain(dfp_lcm_segment_t *s, const uint8_t *buf, size_t len)
{
    dfp_lcm_telegram_t msg;
    char why[96];
    if (len == 0u || dfp_lcm_telegram_decode_checked(buf, len, &msg, why, sizeof why) != 0) {
        drop(s, DFP_SEG_DROP_MALFORMED, why);
        return;
    }
    if (s->keyed && msg.source_id != s->source_id) {
        char detail[96];
        snprintf(detail, sizeof detail, "station %d, source id %lld", msg.station,
                 (long long)msg.source_id);
        drop(s, DFP_SEG_DROP_UNSIGNED, detail);
    } else if (!s->keyed) {
        on_telegram(s, &msg);
    }
    dfp_lcm_telegram_t_decode_cleanup(&msg);
}

/* A signed_telegram_t: its tag, window and sequence first, then the telegram inside. */
static void on_signed(dfp_lcm_segment_t *s, const uint8_t *buf, size_t len)
{
    dfp_seg_msg_t m;
    char detail[96];
    if (dfp_seg_parse(buf, len, &m) != 0) {
        drop(s, DFP_SEG_DROP_MALFORMED, "signed_telegram_t of a wrong layout");
        return;
    }
    if (m.sender_id == s->source_id) {
        s->own_ignored++;
        return;
    }
    snprintf(detail, sizeof detail, "sender id %lld", (long long)m.sender_id);
    if (!s->keyed) {
        drop(s, DFP_SEG_DROP_SIGNED, detail);
        return;
    }
    int why = dfp_seg_verify(&s->auth, s->channel, buf, len, &m, dfp_lcm_wall_us());
    if (why >= 0) {
        drop(s, (dfp_seg_drop_t)why, detail);
        return;
    }
    dfp_lcm_telegram_t msg;
    char err[96];
    if (dfp_lcm_telegram_decode_checked(m.telegram, m.tlen, &msg, err, sizeof err) != 0) {
        drop(s, DFP_SEG_DROP_MALFORMED, err);
        return;
    }
    if (msg.source_id != m.sender_id) {
        drop(s, DFP_SEG_DROP_MALFORMED, "signed by another sender than the telegram's");
    } else {
        on_telegram(s, &msg);
    }
    dfp_lcm_telegram_t_decode_cleanup(&msg);
}

void dfp_lcm_segment_receive(dfp_lcm_segment_t *s, const uint8_t *buf, size_t len)
{
    if (dfp_seg_is_signed(buf, len)) {
        on_signed(s, buf, len);
    } else {
        on_plain(s, buf, len);
    }
}

/* Raw, so that a message that is not a well-formed telegram_t (another program on the same
 * channel, garbage) is counted and dropped instead of reaching lcm-gen's trusting decoder. */
static void on_message(const lcm_recv_buf_t *rbuf, const char *channel, void *user)
{
    (void)channel;
    dfp_lcm_segment_receive(user, rbuf->data, rbuf->data_size);
}

/* LCM's descriptor is readable: hand over what arrived; the runner polls the station next. */
static void segment_readable(void *ctx, hal_time_us_t now)
{
    (void)now;
    dfp_lcm_segment_t *s = ctx;
    for (int i = 0; i < SEGMENT_HANDLE_BURST; i++) {
        int rc = lcm_handle_timeout(s->lcm, 0);
        if (rc == 0) {
            return;
        }
        if (rc < 0) {
            tty_runner_set_error(s->runner, "LCM %s: receiving on %s failed", s->url,
                                 s->channel);
            return;
        }
    }
}

static hal_time_us_t segment_poll(void *ctx, hal_time_us_t now)
{
    dfp_lcm_segment_t *s = ctx;
    dfp_seg_drops_flush(&s->drops, s->channel, mono_us(), log_thunk, s);
    if (s->station.poll == NULL) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    return s->station.poll(s->station.ctx, now);
}

static int segment_set_baud(void *ctx, uint32_t baud)
{
    dfp_lcm_segment_t *s = ctx;
    s->baud = baud;
    return 0;
}

static void wait_until(hal_time_us_t not_before)
{
    for (;;) {
        int32_t wait = hal_time_diff(not_before, tty_now_us());
        if (wait <= 0) {
            return;
        }
        struct timespec ts = {.tv_sec = wait / 1000000, .tv_nsec = (long)(wait % 1000000) * 1000L};
        if (nanosleep(&ts, NULL) == 0) {
            return;
        }
        if (errno != EINTR) {
            return;
        }
    }
}

/* A keyed segment sends the telegram inside a signed_telegram_t. */
static int publish(dfp_lcm_segment_t *s, const dfp_lcm_telegram_t *m)
{
    if (!s->keyed) {
        return dfp_lcm_telegram_t_publish(s->lcm, s->channel, m);
    }
    uint8_t plain[DFP_SEG_TELEGRAM_MAX];
    uint8_t out[DFP_SEG_SIGNED_MAX];
    int n = dfp_lcm_telegram_t_encode(plain, 0, (int)sizeof plain, m);
    if (n <= 0) {
        return -1;
    }
    size_t len = dfp_seg_sign(&s->auth, s->channel, s->source_id,
                              dfp_seg_next_seq(&s->auth, m->utime), plain, (size_t)n, out,
                              sizeof out);
    return len == 0u ? -1 : lcm_publish(s->lcm, s->channel, out, (unsigned)len);
}

static int segment_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    dfp_lcm_segment_t *s = ctx;
    if (len == 0u || len > 512u) {
        return -1;
    }
    if (hal_time_diff(not_before, tty_now_us()) > SEGMENT_MAX_TX_WAIT_US) {
        if (s->runner != NULL) {
            tty_runner_set_error(s->runner, "transmit on %s: not_before more than 10 s ahead",
                                 s->channel);
        }
        return -1;
    }
    wait_until(not_before);
    uint8_t copy[512];
    memcpy(copy, frame, len);
    uint64_t t_ns = host_clock_mono_ns();
    dfp_lcm_telegram_t m = {
        .utime = dfp_lcm_wall_us(),
        .source_id = s->source_id,
        .process_id = s->process_id,
        .station = s->station_address,
        .direction = DFP_LCM_TELEGRAM_T_DIR_TX,
        .baud = (int32_t)s->baud,
        .error_flags = 0,
        .length = (int16_t)len,
        .data = copy,
    };
    if (publish(s, &m) != 0) {
        s->send_failures++;
        if (s->runner != NULL) {
            tty_runner_set_error(s->runner, "LCM %s: sending on %s failed", s->url, s->channel);
        }
        return -1;
    }
    s->frames_sent++;
    if (s->tap != NULL) {
        s->tap(s->tap_ctx, t_ns - s->t0_ns, frame, len, true, s->baud);
    }
    return 0;
}

static const hal_uart_ops_t segment_uart_ops = {
    .set_baud = segment_set_baud,
    .transmit = segment_transmit,
};

int dfp_lcm_segment_open(dfp_lcm_segment_t *s, const char *url, const char *channel,
                         int16_t station_address, uint32_t baud, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (channel == NULL || channel[0] == '\0' || strlen(channel) >= sizeof s->channel) {
        snprintf(err, errlen, "LCM segment: channel name must be 1..%zu characters",
                 sizeof s->channel - 1u);
        return -1;
    }
    snprintf(s->channel, sizeof s->channel, "%s", channel);
    bool given = url != NULL && url[0] != '\0';
    snprintf(s->url, sizeof s->url, "%s", given ? url : dfp_lcm_default_url());
    s->lcm = lcm_create(given ? url : NULL);
    if (s->lcm == NULL) {
        snprintf(err, errlen, "cannot open LCM URL '%s'%s", s->url,
                 strncmp(s->url, "udpm://", 7) == 0
                     ? " (udpm needs a multicast route, e.g. ip route add 239.0.0.0/8 dev lo)"
                     : "");
        return -1;
    }
    lcm_subscription_t *sub = lcm_subscribe(s->lcm, s->channel, on_message, s);
    if (sub == NULL) {
        snprintf(err, errlen, "LCM %s: cannot subscribe to %s", s->url, s->channel);
        lcm_destroy(s->lcm);
        s->lcm = NULL;
        return -1;
    }
    lcm_subscription_set_queue_capacity(sub, DFP_LCM_SEGMENT_QUEUE);
    s->subscription = sub;
    s->source_id = dfp_lcm_new_source_id();
    s->process_id = (int32_t)getpid();
    s->station_address = station_address;
    s->baud = baud;
    s->t0_ns = host_clock_mono_ns();
    return 0;
}

hal_uart_t dfp_lcm_segment_uart(dfp_lcm_segment_t *s)
{
    return (hal_uart_t){.ops = &segment_uart_ops, .ctx = s};
}

int dfp_lcm_segment_attach(dfp_lcm_segment_t *s, tty_runner_t *r, const sim_station_t *st)
{
    int fd = lcm_get_fileno(s->lcm);
    if (fd < 0 || tty_runner_add_fd(r, fd, segment_readable, s) != 0) {
        return -1;
    }
    if (tty_runner_add_timer(r, segment_poll, s) != 0) {
        (void)tty_runner_remove_fd(r, fd);
        return -1;
    }
    s->station = *st;
    s->runner = r;
    s->station_attached = true;
    return 0;
}

void dfp_lcm_segment_set_tap(dfp_lcm_segment_t *s, sim_frame_tap_t tap, void *ctx)
{
    s->tap = tap;
    s->tap_ctx = ctx;
}

int dfp_lcm_segment_set_key(dfp_lcm_segment_t *s, const uint8_t key[DFP_SEG_KEY_BYTES])
{
    if (dfp_seg_auth_init(&s->auth, key) != 0) {
        return -1;
    }
    s->keyed = true;
    return 0;
}

void dfp_lcm_segment_set_log(dfp_lcm_segment_t *s, dfp_seg_log_fn log, void *ctx)
{
    s->log = log;
    s->log_ctx = ctx;
}

static void log_totals(dfp_lcm_segment_t *s)
{
    uint64_t dropped = 0;
    for (unsigned i = 0; i < DFP_SEG_DROP_REASONS; i++) {
        dropped += s->drops.total[i];
    }
    if (!s->keyed && dropped == 0u) {
        return;
    }
    char text[200];
    char line[320];
    snprintf(line, sizeof line, "segment %s%s: %llu telegrams taken, %llu dropped (%s)",
             s->channel, s->keyed ? " (keyed)" : "", (unsigned long long)s->frames_received,
             (unsigned long long)dropped,
             dfp_seg_drops_text(s->drops.total, true, text, sizeof text));
    segment_log(s, line);
}

void dfp_lcm_segment_close(dfp_lcm_segment_t *s)
{
    if (s->runner != NULL) {
        (void)tty_runner_remove_fd(s->runner, lcm_get_fileno(s->lcm));
        (void)tty_runner_remove_timer(s->runner, segment_poll, s);
        s->runner = NULL;
    }
    s->station_attached = false;
    if (s->lcm != NULL) {
        log_totals(s);
        dfp_seg_auth_clear(&s->auth);
        if (s->subscription != NULL) {
            lcm_unsubscribe(s->lcm, s->subscription);
            s->subscription = NULL;
        }
        lcm_destroy(s->lcm);
        s->lcm = NULL;
    }
}
