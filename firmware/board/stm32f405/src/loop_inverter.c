#include "board/loop_inverter.h"

#include <string.h>

static int queue_put(loop_can_queue_t *q, const hal_can_frame_t *f)
{
    if (q->head - q->tail >= LOOP_INVERTER_QUEUE) {
        q->dropped++;
        return -1;
    }
    q->f[q->head % LOOP_INVERTER_QUEUE] = *f;
    q->head++;
    return 0;
}

static int card_send(void *ctx, const hal_can_frame_t *f)
{
    loop_inverter_t *l = ctx;
    return queue_put(&l->to_inverter, f);
}

static int inverter_send(void *ctx, const hal_can_frame_t *f)
{
    loop_inverter_t *l = ctx;
    return queue_put(&l->to_card, f);
}

static const hal_can_ops_t card_ops = {.send = card_send};
static const hal_can_ops_t inverter_ops = {.send = inverter_send};

static void inv_param(void *ctx, const uint8_t req[ML_TELEGRAM_LEN], uint8_t rsp[ML_TELEGRAM_LEN])
{
    loop_inverter_t *l = ctx;
    l->services++;
    memcpy(rsp, req, ML_TELEGRAM_LEN);
    rsp[ML_OFF_MANAGEMENT] &= (uint8_t)~ML_MGMT_HANDSHAKE;
    uint16_t index = ml_index(req);
    uint8_t svc = req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK;
    bool ram = index >= 8600u && index <= 8603u;
    if (svc == ML_SVC_READ && index == 8300u) {
        ml_put_data(rsp, 823947913u);
    } else if (svc == ML_SVC_READ && index == 8301u) {
        ml_put_data(rsp, 0u);
    } else if (svc == ML_SVC_READ && ram) {
        ml_put_data(rsp, l->ram[index - 8600u]);
    } else if ((svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE) && ram) {
        l->ram[index - 8600u] = ml_data(req);
    } else {
        ml_put_error(rsp, ML_CLASS_OTHER, 0u, ML_ADD_ILLEGAL_INDEX);
    }
}

static void inv_po(void *ctx, const uint16_t *po, uint8_t n)
{
    loop_inverter_t *l = ctx;
    for (uint8_t i = 0; i < SBUS_PD_WORDS; i++) {
        l->po[i] = i < n ? po[i] : 0u;
    }
}

static void inv_pi(void *ctx, uint16_t *pi, uint8_t n)
{
    loop_inverter_t *l = ctx;
    for (uint8_t i = 0; i < n && i < SBUS_PD_WORDS; i++) {
        pi[i] = l->po[i];
    }
}

void loop_inverter_init(loop_inverter_t *l, uint8_t sbus_address)
{
    memset(l, 0, sizeof *l);
    sbus_inverter_cfg_t cfg = {.can = {.ops = &inverter_ops, .ctx = l},
                               .address = sbus_address,
                               .channel2 = true,
                               .ctx = l,
                               .param = inv_param,
                               .process_outputs = inv_po,
                               .process_inputs = inv_pi};
    sbus_inverter_init(&l->inv, &cfg);
}

hal_can_t loop_inverter_card_can(loop_inverter_t *l)
{
    return (hal_can_t){.ops = &card_ops, .ctx = l};
}

unsigned loop_inverter_poll(loop_inverter_t *l, hal_time_us_t now, hal_can_rx_fn rx, void *ctx,
                            void (*between)(void *ctx))
{
    unsigned n = 0;
    while (l->to_inverter.tail != l->to_inverter.head) {
        if (n > 0u && between != NULL) {
            between(ctx);
        }
        hal_can_frame_t f = l->to_inverter.f[l->to_inverter.tail % LOOP_INVERTER_QUEUE];
        l->to_inverter.tail++;
        sbus_inverter_rx(&l->inv, &f, now);
        n++;
    }
    while (l->to_card.tail != l->to_card.head) {
        hal_can_frame_t f = l->to_card.f[l->to_card.tail % LOOP_INVERTER_QUEUE];
        l->to_card.tail++;
        rx(ctx, &f);
        n++;
    }
    return n;
}
