#include "lcm_bridge/lcm_bridge.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

#include <lcm/lcm.h>

#include "dfp_lcm/dfp_lcm_card_state_t.h"
#include "dfp_lcm/dfp_lcm_api_event_t.h"
#include "dfp_lcm/dfp_lcm_param_service_t.h"
#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "dp_master/param_channel.h"

int64_t dfp_lcm_wall_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

int64_t dfp_lcm_new_source_id(void)
{
    uint64_t id = 0;
    if (getrandom(&id, sizeof id, GRND_NONBLOCK) != (ssize_t)sizeof id) {
        /* No entropy yet (early boot): pid and time still differ between processes. */
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        id = ((uint64_t)getpid() << 40) ^ (uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 20);
    }
    id &= 0x7FFFFFFFFFFFFFFFull; /* positive: easier to read in lcm-spy */
    return id != 0u ? (int64_t)id : 1;
}

const char *dfp_lcm_default_url(void)
{
    const char *env = getenv("LCM_DEFAULT_URL");
    return env != NULL && env[0] != '\0' ? env : "udpm://239.255.76.67:7667?ttl=0";
}

const char *dfp_lcm_param_path(uint8_t channel)
{
    switch (channel) {
    case DFP21B_CH_CYCLIC: return "channel";
    case DFP21B_CH_C1: return "c1-ds47";
    case DFP21B_CH_C2_FIRST: return "c2-ds47-1";
    case DFP21B_CH_C2_FIRST + 1u: return "c2-ds47-2";
    case DFP21B_CH_STATUS_POLL: return "status-poll";
    default: return "?";
    }
}

static void failed(dfp_lcm_bridge_t *b, const char *what)
{
    b->failures++;
    if (b->error[0] == '\0') {
        snprintf(b->error, sizeof b->error, "LCM %s: publishing %s failed", b->url, what);
    }
}

int dfp_lcm_bridge_open(dfp_lcm_bridge_t *b, const char *url, int16_t station, char *err,
                        size_t errlen)
{
    memset(b, 0, sizeof *b);
    snprintf(b->url, sizeof b->url, "%s",
             url != NULL && url[0] != '\0' ? url : dfp_lcm_default_url());
    b->lcm = lcm_create(url != NULL && url[0] != '\0' ? url : NULL);
    if (b->lcm == NULL) {
        snprintf(err, errlen,
                 "cannot open LCM URL '%s'%s", b->url,
                 strncmp(b->url, "udpm://", 7) == 0
                     ? " (udpm needs a multicast route, e.g. ip route add 239.0.0.0/8 dev lo)"
                     : "");
        return -1;
    }
    b->source_id = dfp_lcm_new_source_id();
    b->process_id = (int32_t)getpid();
    b->station = station;
    b->state_interval_ms = DFP_LCM_STATE_INTERVAL_MS_DEFAULT;
    return 0;
}

void dfp_lcm_bridge_close(dfp_lcm_bridge_t *b)
{
    if (b->lcm != NULL) {
        lcm_destroy(b->lcm);
        b->lcm = NULL;
    }
}

int dfp_lcm_bridge_telegram(dfp_lcm_bridge_t *b, int64_t utime, const uint8_t *frame,
                            size_t len, bool from_local, uint32_t baud, uint16_t error_flags)
{
    if (b->lcm == NULL) {
        return -1;
    }
    uint8_t copy[512];
    if (len > sizeof copy) {
        len = sizeof copy; /* no FDL telegram is that long; keep what fits */
    }
    memcpy(copy, frame, len);
    dfp_lcm_telegram_t m = {
        .utime = utime,
        .source_id = b->source_id,
        .process_id = b->process_id,
        .station = b->station,
        .direction = from_local ? DFP_LCM_TELEGRAM_T_DIR_TX : DFP_LCM_TELEGRAM_T_DIR_RX,
        .baud = (int32_t)baud,
        .error_flags = (int16_t)error_flags,
        .length = (int16_t)len,
        .data = copy,
    };
    if (dfp_lcm_telegram_t_publish(b->lcm, DFP_LCM_CH_TELEGRAM, &m) != 0) {
        failed(b, "a telegram");
        return -1;
    }
    b->messages++;
    return 0;
}

static void snapshot(const dfp21b_t *c, dfp_lcm_state_snapshot_t *s)
{
    memset(s, 0, sizeof *s); /* compared with memcmp: padding must be equal too */
    s->dp_state = (uint8_t)dp_slave_state(&c->dp);
    s->led_run = (uint8_t)c->led[HAL_LED_RUN];
    s->led_bus_fault = (uint8_t)c->led[HAL_LED_BUS_FAULT];
    s->address = dfp21b_p093_address(c);
    s->baud = dfp21b_p092_baud(c);
    s->pd_valid = c->pd.valid;
    s->param_channel = c->pd.valid && c->pd.param_channel;
    s->pd_words = c->pd.valid ? c->pd.pd_words : 0u;
    if (s->pd_words > DFP21B_MAX_PD) {
        s->pd_words = DFP21B_MAX_PD;
    }
    s->p819_ms = dfp21b_p819_timeout_ms(c);
    for (uint8_t i = 0; i < s->pd_words; i++) {
        s->po[i] = c->po[i];
        s->pi[i] = c->pi[i];
    }
}

static int publish_state(dfp_lcm_bridge_t *b, int64_t utime, const dfp21b_t *c,
                         const dfp_lcm_state_snapshot_t *s)
{
    char p090[16];
    dfp21b_p090_text(&c->pd, p090, sizeof p090);
    int32_t po[DFP21B_MAX_PD];
    int32_t pi[DFP21B_MAX_PD];
    for (uint8_t i = 0; i < DFP21B_MAX_PD; i++) {
        po[i] = s->po[i];
        pi[i] = s->pi[i];
    }
    dfp_lcm_card_state_t m = {
        .utime = utime,
        .source_id = b->source_id,
        .address = s->address,
        .dp_state = (char *)dp_state_name((dp_state_t)s->dp_state),
        .dp_state_num = (int8_t)s->dp_state,
        .led_run = (char *)hal_led_mode_name((hal_led_mode_t)s->led_run),
        .led_run_mode = (int8_t)s->led_run,
        .led_bus_fault = (char *)hal_led_mode_name((hal_led_mode_t)s->led_bus_fault),
        .led_bus_fault_mode = (int8_t)s->led_bus_fault,
        .baud = (int32_t)s->baud,
        .p090_pd_config = p090,
        .p091_fieldbus_type = (char *)"PROFIBUS DP",
        .p092_baud = (int32_t)s->baud,
        .p093_address = s->address,
        .p094_po1 = s->pd_words > 0u ? po[0] : 0,
        .p095_po2 = s->pd_words > 1u ? po[1] : 0,
        .p096_po3 = s->pd_words > 2u ? po[2] : 0,
        .p097_pi1 = s->pd_words > 0u ? pi[0] : 0,
        .p098_pi2 = s->pd_words > 1u ? pi[1] : 0,
        .p099_pi3 = s->pd_words > 2u ? pi[2] : 0,
        .p819_timeout_ms = (int32_t)s->p819_ms,
        .param_channel = s->param_channel ? 1 : 0,
        .pd_words = (int8_t)s->pd_words,
        .po = po,
        .pi = pi,
    };
    if (dfp_lcm_card_state_t_publish(b->lcm, DFP_LCM_CH_CARD_STATE, &m) != 0) {
        failed(b, "the card state");
        return -1;
    }
    b->messages++;
    return 1;
}

/* Member by member: the struct has padding, which memcmp would compare too. */
static bool snapshot_equal(const dfp_lcm_state_snapshot_t *a, const dfp_lcm_state_snapshot_t *b)
{
    if (a->dp_state != b->dp_state || a->led_run != b->led_run ||
        a->led_bus_fault != b->led_bus_fault || a->address != b->address || a->baud != b->baud ||
        a->pd_valid != b->pd_valid || a->param_channel != b->param_channel ||
        a->pd_words != b->pd_words || a->p819_ms != b->p819_ms) {
        return false;
    }
    for (size_t i = 0; i < DFP21B_MAX_PD; i++) {
        if (a->po[i] != b->po[i] || a->pi[i] != b->pi[i]) {
            return false;
        }
    }
    return true;
}

int dfp_lcm_bridge_card_state(dfp_lcm_bridge_t *b, int64_t utime, const dfp21b_t *card)
{
    if (b->lcm == NULL) {
        return -1;
    }
    dfp_lcm_state_snapshot_t s;
    snapshot(card, &s);
    if (b->state_published && snapshot_equal(&s, &b->last)) {
        b->state_pending = false;
        return 0;
    }
    if (b->state_published && utime - b->state_utime < (int64_t)b->state_interval_ms * 1000) {
        b->state_pending = true;
        return 0;
    }
    /* Counted as published even when it failed: a broken URL is not retried every cycle. */
    b->last = s;
    b->state_published = true;
    b->state_utime = utime;
    b->state_pending = false;
    return publish_state(b, utime, card, &s);
}

int dfp_lcm_bridge_param_service(dfp_lcm_bridge_t *b, int64_t utime, uint8_t channel,
                                 const uint8_t req[ML_TELEGRAM_LEN],
                                 const uint8_t rsp[ML_TELEGRAM_LEN])
{
    if (b->lcm == NULL) {
        return -1;
    }
    uint8_t service = req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK;
    bool ok = (rsp[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) == 0u;
    char text[128] = "";
    if (!ok) {
        ml_error_text(rsp, text, sizeof text);
    }
    bool writes = service == ML_SVC_WRITE || service == ML_SVC_WRITE_VOLATILE;
    uint32_t value = ok && !writes ? ml_data(rsp) : ml_data(req);
    dfp_lcm_param_service_t m = {
        .utime = utime,
        .source_id = b->source_id,
        .address = b->station,
        .path = (char *)dfp_lcm_param_path(channel),
        .link_channel = (int8_t)channel,
        .index = ml_index(req),
        .subindex = req[ML_OFF_RESERVED],
        .service = (char *)ml_service_name(service),
        .service_num = (int8_t)service,
        .value = value,
        .ok = ok ? 1 : 0,
        .result = ok ? 0 : (int32_t)ml_data(rsp),
        .result_text = text,
    };
    memcpy(m.request, req, ML_TELEGRAM_LEN);
    memcpy(m.response, rsp, ML_TELEGRAM_LEN);
    if (dfp_lcm_param_service_t_publish(b->lcm, DFP_LCM_CH_PARAM, &m) != 0) {
        failed(b, "a parameter service");
        return -1;
    }
    b->messages++;
    return 0;
}

int dfp_lcm_bridge_api_event(dfp_lcm_bridge_t *b, int64_t utime, int64_t t_us, int64_t seq,
                             const char *level, const char *kind, const char *text)
{
    if (b->lcm == NULL) {
        return -1;
    }
    dfp_lcm_api_event_t m = {
        .utime = utime,
        .source_id = b->source_id,
        .t_us = t_us,
        .seq = seq,
        .level = (char *)level,
        .kind = (char *)kind,
        .text = (char *)text,
    };
    if (dfp_lcm_api_event_t_publish(b->lcm, DFP_LCM_CH_API, &m) != 0) {
        failed(b, "an API event");
        return -1;
    }
    b->messages++;
    return 0;
}

void dfp_lcm_bridge_param_observer(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                                   const uint8_t rsp[ML_TELEGRAM_LEN])
{
    dfp_lcm_bridge_t *b = ctx;
    int64_t utime = b->clock != NULL ? b->clock(b->clock_ctx) : dfp_lcm_wall_us();
    (void)dfp_lcm_bridge_param_service(b, utime, channel, req, rsp);
}
