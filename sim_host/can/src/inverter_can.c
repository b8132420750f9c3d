/* SBus card link on SocketCAN inside the tty runner. See inverter_can.h. */
#include "can/inverter_can.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int inverter_can_parse(const char *spec, char *ifname, size_t ifname_len, uint8_t *address,
                       char *err, size_t errlen)
{
    const char *p = spec;
    if (strncmp(p, "can:", 4) == 0) {
        p += 4;
    }
    const char *colon = strchr(p, ':');
    size_t n = colon != NULL ? (size_t)(colon - p) : strlen(p);
    if (n == 0u || n >= ifname_len) {
        (void)snprintf(err, errlen, "--inverter %s: expected can:IFACE[:ADDR], e.g. can:vcan0:1",
                       spec);
        return -1;
    }
    memcpy(ifname, p, n);
    ifname[n] = '\0';
    *address = 0;
    if (colon != NULL) {
        char *end = NULL;
        unsigned long a = strtoul(colon + 1, &end, 10);
        if (colon[1] == '\0' || *end != '\0' || a > SBUS_MAX_ADDRESS) {
            (void)snprintf(err, errlen, "--inverter %s: SBus address must be 0..63", spec);
            return -1;
        }
        *address = (uint8_t)a;
    }
    return 0;
}

static void inverter_can_rx(void *ctx, const hal_can_frame_t *f)
{
    inverter_can_t *l = ctx;
    sbus_card_link_rx(&l->link, f, tty_now_us());
}

static hal_time_us_t inverter_can_timer(void *ctx, hal_time_us_t now)
{
    inverter_can_t *l = ctx;
    return sbus_card_link_poll(&l->link, now);
}

int inverter_can_open(inverter_can_t *l, const char *spec,
                      void (*param_response)(void *card, uint8_t channel,
                                             const uint8_t rsp[ML_TELEGRAM_LEN]),
                      void (*process_inputs)(void *card, const uint16_t *pi, uint8_t n),
                      void *card, tty_runner_t *runner, char *err, size_t errlen)
{
    memset(l, 0, sizeof *l);
    l->sock.fd = -1;
    if (inverter_can_parse(spec, l->ifname, sizeof l->ifname, &l->address, err, errlen) != 0) {
        return -1;
    }
    if (socketcan_open(&l->sock, l->ifname, inverter_can_rx, l, err, errlen) != 0) {
        return -1;
    }
    sbus_card_link_cfg_t cfg = {
        .can = socketcan_can(&l->sock),
        .address = l->address,
        .param_response = param_response,
        .process_inputs = process_inputs,
        .card = card,
    };
    sbus_card_link_init(&l->link, &cfg);
    if (socketcan_attach(&l->sock, runner) != 0 ||
        tty_runner_add_timer(runner, inverter_can_timer, l) != 0) {
        (void)snprintf(err, errlen, "CAN interface %s: the runner has no room for it", l->ifname);
        socketcan_close(&l->sock);
        (void)tty_runner_remove_timer(runner, inverter_can_timer, l);
        return -1;
    }
    l->runner = runner;
    return 0;
}

/* The SBus link's own operations, plus a wake-up of the deadline timer after a request: the
 * card asks from inside its station poll, and the runner would otherwise only look at the timer
 * again at its old deadline. */
static int wrap_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    inverter_can_t *l = ctx;
    ml_link_t s = sbus_card_link(&l->link);
    int rc = s.ops->param_request(s.ctx, channel, req);
    if (l->runner != NULL) {
        tty_runner_wake(l->runner);
    }
    return rc;
}

static void wrap_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    inverter_can_t *l = ctx;
    ml_link_t s = sbus_card_link(&l->link);
    s.ops->process_outputs(s.ctx, po, n);
}

static void wrap_fieldbus_status(void *ctx, const ml_fieldbus_status_t *st)
{
    inverter_can_t *l = ctx;
    ml_link_t s = sbus_card_link(&l->link);
    s.ops->fieldbus_status(s.ctx, st);
}

static void wrap_param_cancel(void *ctx, uint8_t channel)
{
    inverter_can_t *l = ctx;
    ml_link_t s = sbus_card_link(&l->link);
    s.ops->param_cancel(s.ctx, channel);
}

static const ml_link_ops_t inverter_can_ops = {
    .param_request = wrap_param_request,
    .process_outputs = wrap_process_outputs,
    .fieldbus_status = wrap_fieldbus_status,
    .param_cancel = wrap_param_cancel,
};

ml_link_t inverter_can_link(inverter_can_t *l)
{
    return (ml_link_t){.ops = &inverter_can_ops, .ctx = l};
}

void inverter_can_close(inverter_can_t *l)
{
    if (l->runner != NULL) {
        (void)tty_runner_remove_timer(l->runner, inverter_can_timer, l);
        l->runner = NULL;
    }
    socketcan_close(&l->sock);
}
