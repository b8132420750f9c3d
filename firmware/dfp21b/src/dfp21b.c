#include "dfp21b/dfp21b.h"
#include "hal/hal_byte_order.h"

#include <string.h>

#include "dp_slave/dp_wire.h"

const uint8_t dfp21b_default_cfg[2] = {0xF3u, 0xF2u};

/* The parameter channel's identifiers (manual §4.1): 4 I/O words or 8 I/O octets, consistent
 * over the whole length. */
#define CFG_PARAM_CHANNEL_WORDS DP_CFG_GENERAL(DP_CFG_CONSISTENT | DP_CFG_WORDS | DP_CFG_DIR_INOUT, 4u)
#define CFG_PARAM_CHANNEL_OCTETS DP_CFG_GENERAL(DP_CFG_CONSISTENT | DP_CFG_DIR_INOUT, 8u)
/* The station address: DIP switches 2^0..2^6 (manual §3.2, protocol.md §B1). */
#define DIP_ADDRESS_MASK 0x7Fu
/* P090 codes beyond the predefined configurations (protocol.md §C4). */
#define P090_UNIVERSAL 254u
#define P090_NONE 255u
/* Status word 1 (protocol.md §C3.3): bit 5 fault/warning, the high octet its number. */
#define STATUS_WORD_FAULT 0x20u
#define STATUS_WORD_FAULT_SHIFT 8u

/* ---- configuration (manual §4.1, §8.1; protocol.md §B3) -------------------------------------- */

typedef struct ident_info {
    uint8_t dir;   /* DP_CFG_DIR_* */
    uint8_t bytes; /* length in octets */
    bool words;
    bool consistent;
} ident_info_t;

static bool decode_general(uint8_t b, ident_info_t *info)
{
    info->dir = (uint8_t)(b & DP_CFG_DIR_MASK);
    if (info->dir == DP_CFG_DIR_SPECIAL) {
        return false;
    }
    info->words = (b & DP_CFG_WORDS) != 0u;
    info->consistent = (b & DP_CFG_CONSISTENT) != 0u;
    uint8_t units = (uint8_t)((b & DP_CFG_LEN_MASK) + 1u);
    info->bytes = (uint8_t)(info->words ? units * 2u : units);
    return true;
}

static bool is_param_channel(uint8_t b)
{
    return b == CFG_PARAM_CHANNEL_WORDS || b == CFG_PARAM_CHANNEL_OCTETS;
}

/* Process-data module: one I/O identifier, or an output and an input identifier. Lengths in
 * octets; *equal reports whether input and output lengths match. */
static bool decode_pd(const uint8_t *cfg, size_t len, uint8_t *out_bytes, uint8_t *in_bytes)
{
    *out_bytes = 0;
    *in_bytes = 0;
    if (len < 1u || len > 2u) {
        return false;
    }
    for (size_t i = 0; i < len; i++) {
        ident_info_t id;
        if (!decode_general(cfg[i], &id) || !id.consistent) {
            return false;
        }
        if (id.dir == DP_CFG_DIR_INOUT) {
            if (len != 1u) {
                return false;
            }
            *out_bytes = id.bytes;
            *in_bytes = id.bytes;
        } else if (id.dir == DP_CFG_DIR_OUT && *out_bytes == 0u) {
            *out_bytes = id.bytes;
        } else if (id.dir == DP_CFG_DIR_IN && *in_bytes == 0u) {
            *in_bytes = id.bytes;
        } else {
            return false;
        }
    }
    return true;
}

bool dfp21b_check_cfg(const uint8_t *cfg, size_t len, dfp21b_pd_cfg_t *pd)
{
    *pd = (dfp21b_pd_cfg_t){0};
    if (cfg == NULL || len == 0u || len > 3u) {
        return false;
    }
    size_t first = 0;
    bool param = false;
    if (len >= 2u && (cfg[0] == 0x00u || is_param_channel(cfg[0]))) {
        /* module 0: an empty slot or the parameter channel */
        param = cfg[0] != 0x00u;
        first = 1;
    }
    uint8_t out_bytes;
    uint8_t in_bytes;
    if (!decode_pd(&cfg[first], len - first, &out_bytes, &in_bytes)) {
        return false;
    }
    /* Unequal lengths are a configuration fault the manual names: P090 shows 0PD. */
    if (out_bytes != in_bytes || out_bytes < 2u || out_bytes > 2u * DFP21B_MAX_PD ||
        (out_bytes % 2u) != 0u) {
        return false;
    }
    pd->valid = true;
    pd->param_channel = param;
    pd->pd_words = (uint8_t)(out_bytes / 2u);
    return true;
}

/* ---- user parameters (manual §4.2; protocol.md §B4) ------------------------------------------- */

bool dfp21b_check_user_prm(const uint8_t *prm, size_t len, bool *diag_alarm)
{
    static const uint8_t block[5] = {0x06u, 0x81u, 0x00u, 0x00u, 0x01u};
    if (len != DFP21B_USER_PRM_LEN) {
        return false;
    }
    /* Octets 0..2 are DPV1_Status_1..3. The card supports DP-V1 read/write but no alarms,
     * no fail-safe, no publisher and no isochronous mode. */
    if ((prm[0] & (uint8_t)~(DP_DPV1_1_ENABLE | DP_DPV1_1_WD_BASE_1MS |
                             DP_DPV1_1_DIS_STOP_CONTROL | DP_DPV1_1_DIS_START_CONTROL)) != 0u) {
        return false;
    }
    if (prm[1] != 0u) {
        return false;
    }
    if ((prm[2] & (uint8_t)~(DP_DPV1_3_PRM_STRUCTURE | DP_DPV1_3_ALARM_MODE_MASK)) != 0u) {
        return false;
    }
    if (memcmp(&prm[3], block, sizeof block) != 0 || prm[8] > 1u) {
        return false;
    }
    /* The manual (§4.2) defines this external diagnosis for DP-V0 only: in DP-V1 mode the
     * device-related diagnosis has the alarm/status block format, which a 2-octet block would
     * violate. Accept the Set_Prm (the master may offer the GSD's choice) but stay silent. */
    *diag_alarm = prm[8] == 0u && (prm[0] & DP_DPV1_1_ENABLE) == 0u;
    return true;
}

size_t dfp21b_p090_text(const dfp21b_pd_cfg_t *pd, char *out, size_t max)
{
    char buf[16];
    size_t n = 0;
    if (!pd->valid) {
        buf[n++] = '0';
    } else {
        if (pd->pd_words >= DFP21B_MAX_PD) { /* 10 PD: the only two-digit count */
            buf[n++] = '1';
            buf[n++] = '0';
        } else {
            buf[n++] = (char)('0' + pd->pd_words);
        }
    }
    buf[n++] = 'P';
    buf[n++] = 'D';
    if (pd->valid && pd->param_channel) {
        static const char suffix[] = " + PARAM";
        memcpy(&buf[n], suffix, sizeof suffix - 1u);
        n += sizeof suffix - 1u;
    }
    if (max == 0u) {
        return 0;
    }
    if (n > max - 1u) {
        n = max - 1u;
    }
    memcpy(out, buf, n);
    out[n] = '\0';
    return n;
}

/* ---- LEDs (manual §3.7; protocol.md §B2) ------------------------------------------------------ */

static void led_set(dfp21b_t *c, hal_led_id_t id, hal_led_mode_t mode)
{
    if (c->leds_known && c->led[id] == mode) {
        return;
    }
    c->led[id] = mode;
    if (c->cfg.led.ops != NULL && c->cfg.led.ops->set != NULL) {
        c->cfg.led.ops->set(c->cfg.led.ctx, id, mode);
    }
}

static void update_leds(dfp21b_t *c)
{
    hal_led_mode_t run = c->on_bus ? HAL_LED_ON : HAL_LED_BLINK;
    hal_led_mode_t bus;
    if (!c->on_bus || !dp_slave_line_active(&c->dp) || c->master_lost) {
        bus = HAL_LED_ON; /* no baud rate, bus interrupted, or master gone (watchdog) */
    } else if (dp_slave_state(&c->dp) == DP_STATE_DATA_EXCH) {
        bus = HAL_LED_OFF;
    } else {
        bus = HAL_LED_BLINK; /* baud found, but not (or wrongly) configured */
    }
    led_set(c, HAL_LED_RUN, run);
    led_set(c, HAL_LED_BUS_FAULT, bus);
    c->leds_known = true;
}

/* ---- hooks from the DP slave (receive path: copy only) ------------------------------------ */

static bool hook_prm_check(void *ctx, const uint8_t *prm, size_t len)
{
    dfp21b_t *c = ctx;
    bool alarm = false;
    if (!dfp21b_check_user_prm(prm, len, &alarm)) {
        return false;
    }
    c->diag_alarm = alarm;
    return true;
}

static bool hook_cfg_check(void *ctx, const uint8_t *cfg, size_t len, uint8_t *out_len,
                           uint8_t *in_len)
{
    dfp21b_t *c = ctx;
    if (!dfp21b_check_cfg(cfg, len, &c->pd_candidate)) {
        return false;
    }
    uint8_t n = (uint8_t)((c->pd_candidate.param_channel ? DFP21B_PARAM_LEN : 0u) +
                          2u * c->pd_candidate.pd_words);
    *out_len = n;
    *in_len = n;
    return true;
}

/* No copy on the reply path: take_outputs() reads dp_slave's image, which holds what the
 * latest call handed over until the next one. */
static void hook_outputs(void *ctx, const uint8_t *out, size_t len, dp_outputs_reason_t why)
{
    dfp21b_t *c = ctx;
    (void)out;
    (void)len;
    c->outputs_new = true;
    c->outputs_reason = why;
}

static dp_sap_answer_t hook_sap_request(void *ctx, uint8_t master, uint8_t dsap, uint8_t ssap,
                                        const uint8_t *data, size_t len, dp_sap_reply_t *reply,
                                        hal_time_us_t t)
{
    dfp21b_t *c = ctx;
    return dpv1_sap_request(&c->dpv1, master, dsap, ssap, data, len, reply, t);
}

static void hook_event(void *ctx, const dp_event_t *ev)
{
    dfp21b_t *c = ctx;
    bool leds_change = ev->type != DP_EV_RX_ERROR && ev->type != DP_EV_FCB_REPEAT;
    if (ev->type == DP_EV_STATE || ev->type == DP_EV_PRM_OK) {
        /* MSAC1 follows the DP state; a new Set_Prm (even in Data_Exch) closes it. */
        dpv1_dp_state(&c->dpv1,
                      ev->type == DP_EV_STATE && ev->new_state == DP_STATE_DATA_EXCH,
                      dp_slave_dpv1_mode(&c->dp), dp_slave_master(&c->dp));
    }
    switch (ev->type) {
    case DP_EV_WD_EXPIRED:
        leds_change = false; /* the state change that always follows updates them */
        c->master_lost = true;
        c->fieldbus_timeout = true;
        if (c->cfg.app.fieldbus_timeout != NULL) {
            c->cfg.app.fieldbus_timeout(c->cfg.app.ctx);
        }
        break;
    case DP_EV_ADDRESSED:
        /* Every telegram for this station: it can only turn BUS FAULT from on (no line, or the
         * master lost) to off or blinking, so the reply path does not recompute the LEDs each
         * time. */
        leds_change = c->master_lost || !c->leds_known || c->led[HAL_LED_BUS_FAULT] == HAL_LED_ON;
        c->master_lost = false;
        break;
    case DP_EV_PRM_OK:
        c->p819_ms = ev->value;
        /* 0 stays "never parameterised": the inverter keeps its P819 until a master sets it. */
        c->prm_count = (uint8_t)(c->prm_count == UINT8_MAX ? 1u : c->prm_count + 1u);
        /* The master may have switched the diagnostic alarm (user prm octet 8): report the
         * fault that is active now under the new setting. */
        dfp21b_set_inverter_fault(c, c->inverter_fault);
        break;
    case DP_EV_CFG_OK:
        c->pd = c->pd_candidate;
        break;
    case DP_EV_CFG_FAULT:
        c->pd = (dfp21b_pd_cfg_t){0};
        break;
    case DP_EV_STATE:
        if (ev->new_state == DP_STATE_DATA_EXCH) {
            /* Telegrams are back: a P831 warning clears. The parameter channel keeps its
             * handshake and reply across the interruption: the master's outputs still carry
             * its last request, and re-initialising would run it again or never. */
            c->fieldbus_timeout = false;
            c->inputs_dirty = true;
        }
        break;
    default:
        break;
    }
    if (ev->type != DP_EV_ADDRESSED && ev->type != DP_EV_RX_ERROR &&
        ev->type != DP_EV_FCB_REPEAT) {
        c->status_dirty = true;
    }
    if (leds_change) {
        update_leds(c);
    }
    if (c->cfg.event != NULL) {
        c->cfg.event(c->cfg.event_ctx, ev);
    }
}

/* ---- life cycle ---------------------------------------------------------------------------- */

/* Out of line, as init_dp: each configuration struct lives only in its own frame, so they do
 * not add up on the stack (the card's stack reservation comes from the deepest chain). */
__attribute__((noinline)) static void init_dpv1(dfp21b_t *c, const dfp21b_cfg_t *cfg)
{
    dpv1_cfg_t vcfg = {
        .ml = &c->ml,
        .preempt = cfg->preempt,
        .preempt_ctx = cfg->preempt_ctx,
        .ch_c1 = DFP21B_CH_C1,
        .ch_c2 = {DFP21B_CH_C2_FIRST, DFP21B_CH_C2_FIRST + 1u},
        .identity = {.manufacturer_id = DFP21B_MANUFACTURER_ID,
                     .order_id = DFP21B_ORDER_ID,
                     .hardware_revision = cfg->hardware_revision,
                     .software_revision = {'V', cfg->software_revision[0],
                                           cfg->software_revision[1], cfg->software_revision[2]},
                     .profile_id = 0x0000u},
        .nvm = cfg->nvm,
        .nvm_offset = 0,
    };
    if (cfg->serial != NULL) {
        size_t n = 0;
        while (n < sizeof vcfg.identity.serial - 1u && cfg->serial[n] != '\0') {
            vcfg.identity.serial[n] = cfg->serial[n];
            n++;
        }
    }
    dpv1_init(&c->dpv1, &vcfg);
}

__attribute__((noinline)) static void init_dp(dfp21b_t *c, const dfp21b_cfg_t *cfg,
                                              hal_time_us_t now)
{
    dp_slave_cfg_t dcfg = {
        .address = c->address,
        .ident = DFP21B_IDENT,
        .fixed_baud = cfg->fixed_baud,
        .strict_timing = cfg->strict_timing,
        .baud_control_ms = cfg->baud_control_ms,
        .sync_supported = true,
        .freeze_supported = true,
        .default_cfg = dfp21b_default_cfg,
        .default_cfg_len = (uint8_t)sizeof dfp21b_default_cfg,
        .uart = c->on_bus ? cfg->uart : (hal_uart_t){0},
        .hooks = {.ctx = c, .prm_check = hook_prm_check, .cfg_check = hook_cfg_check,
                  .outputs = hook_outputs, .event = hook_event, .sap_request = hook_sap_request},
    };
    dp_slave_init(&c->dp, &dcfg, now);
}

void dfp21b_init(dfp21b_t *c, const dfp21b_cfg_t *cfg, hal_time_us_t now)
{
    memset(c, 0, sizeof *c);
    c->cfg = *cfg;
    uint8_t dip = 0;
    if (cfg->dip.ops != NULL && cfg->dip.ops->read != NULL) {
        dip = cfg->dip.ops->read(cfg->dip.ctx);
    }
    c->address = (uint8_t)(dip & DIP_ADDRESS_MASK);
    c->on_bus = c->address <= DFP21B_MAX_ADDRESS;
    ml_client_init(&c->ml, cfg->inverter, 0);
    ml_channel_init(&c->param, &c->ml, DFP21B_CH_CYCLIC);
    init_dpv1(c, cfg);
    c->status_dirty = true;
    c->now = now;
    c->next_status_poll = now; /* a timestamp, never 0: see hal_time_diff() */
    init_dp(c, cfg, now);
    update_leds(c);
}

#if FDL_RX_CHAR_INPUT
void dfp21b_rx_char(dfp21b_t *c, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    if (c->on_bus) {
        dp_slave_rx_char(&c->dp, byte, flags, t);
    }
}
#endif

void dfp21b_rx_telegram(dfp21b_t *c, const fdl_rx_telegram_t *tg)
{
    if (c->on_bus) {
        dp_slave_rx_telegram(&c->dp, tg);
    }
}

/* P090 codes of the predefined configurations (protocol.md §C4); a universal module that is
 * not one of them shows 254, no valid configuration 255 ("0PD"). */
static uint8_t p090_code(const dfp21b_pd_cfg_t *pd)
{
    if (!pd->valid) {
        return P090_NONE;
    }
    static const uint8_t words[] = {1u, 2u, 3u, 6u, 10u};
    for (uint8_t i = 0; i < (uint8_t)sizeof words; i++) {
        if (pd->pd_words == words[i]) {
            return (uint8_t)(2u * i + (pd->param_channel ? 0u : 1u));
        }
    }
    return P090_UNIVERSAL;
}

static void push_fieldbus_status(dfp21b_t *c)
{
    c->status_dirty = false;
    if (c->cfg.inverter.ops == NULL || c->cfg.inverter.ops->fieldbus_status == NULL) {
        return;
    }
    ml_fieldbus_status_t st = {
        .pd_config = p090_code(&c->pd),
        .pd_words = c->pd.valid ? c->pd.pd_words : 0u,
        .param_channel = c->pd.valid && c->pd.param_channel,
        .baud = c->on_bus ? dfp21b_p092_baud(c) : 0u, /* off the bus nothing is heard */
        .address = c->address,
        .watchdog_ms = c->p819_ms,
        .prm_count = c->prm_count,
        .data_exchange = dp_slave_state(&c->dp) == DP_STATE_DATA_EXCH,
        .timeout = c->fieldbus_timeout,
    };
    c->cfg.inverter.ops->fieldbus_status(c->cfg.inverter.ctx, &st);
}

static bool have_inverter(const dfp21b_t *c)
{
    return c->cfg.inverter.ops != NULL;
}

/* New outputs from the master: parameter channel and PO words go to the inverter. */
static void take_outputs(dfp21b_t *c, hal_time_us_t now)
{
    const uint8_t *out = dp_slave_outputs(&c->dp);
    size_t off = c->pd.param_channel ? DFP21B_PARAM_LEN : 0u;
    uint8_t n = c->pd.valid ? c->pd.pd_words : 0u;
    if (c->pd.param_channel) {
        memcpy(c->param_req, out, DFP21B_PARAM_LEN);
    }
    for (uint8_t i = 0; i < DFP21B_MAX_PD; i++) {
        uint16_t w = 0u;
        if (i < n) {
            size_t at = off + 2u * (size_t)i;
            w = (uint16_t)((out[at] << 8) | out[at + 1u]);
        }
        c->po[i] = w;
    }
    if (have_inverter(c)) {
        /* Only a master's telegram carries a parameter request; cleared or safe-state outputs
         * are zeros, not a request with handshake 0. */
        if (c->pd.param_channel && c->outputs_reason == DP_OUTPUTS_DATA) {
            ml_channel_request(&c->param, c->param_req, now);
        }
        /* Leaving Data_Exch is not a setpoint: the inverter reacts through P831 instead. */
        if (c->outputs_reason != DP_OUTPUTS_SAFE_STATE && c->cfg.inverter.ops->process_outputs) {
            c->cfg.inverter.ops->process_outputs(c->cfg.inverter.ctx, c->po, n);
        }
    } else {
        if (c->cfg.app.process_data != NULL) {
            c->cfg.app.process_data(c->cfg.app.ctx, c->po, c->pi, n, c->outputs_reason);
        } else {
            memcpy(c->pi, c->po, sizeof c->pi); /* loopback: a defined answer without inverter */
        }
        if (c->pd.param_channel && c->cfg.app.param_channel != NULL) {
            c->cfg.app.param_channel(c->cfg.app.ctx, c->param_req, c->param_rsp);
        }
    }
    c->inputs_dirty = true;
}

/* The input image the next Data_Exchange reply carries: parameter reply + PI words. Returns its
 * length. */
static size_t build_inputs(dfp21b_t *c)
{
    size_t off = c->pd.param_channel ? DFP21B_PARAM_LEN : 0u;
    uint8_t n = c->pd.valid ? c->pd.pd_words : 0u;
    if (c->pd.param_channel) {
        memcpy(c->in_image,
               have_inverter(c) ? ml_channel_reply(&c->param) : c->param_rsp, DFP21B_PARAM_LEN);
    }
    for (uint8_t i = 0; i < n; i++) {
        hal_put_be16(&c->in_image[off + 2u * (size_t)i], c->pi[i]);
    }
    return off + 2u * (size_t)n;
}

void dfp21b_inverter_param_response(dfp21b_t *c, uint8_t channel,
                                    const uint8_t rsp[ML_TELEGRAM_LEN])
{
    ml_client_response(&c->ml, channel, rsp);
    c->inputs_dirty = true;
}

void dfp21b_inverter_process_inputs(dfp21b_t *c, const uint16_t *pi, uint8_t n)
{
    if (n > DFP21B_MAX_PD) {
        n = DFP21B_MAX_PD;
    }
    memcpy(c->pi, pi, n * sizeof pi[0]);
    c->inputs_dirty = true;
}

/* Status word 1 (low word of index 8310): bit 5 fault/warning, high byte its number. */
static void on_status(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)channel;
    dfp21b_t *c = ctx;
    c->status_poll_busy = false;
    if ((rsp[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        return;
    }
    uint16_t sw = (uint16_t)ml_data(rsp);
    dfp21b_set_inverter_fault(
        c, (sw & STATUS_WORD_FAULT) != 0u ? (uint8_t)(sw >> STATUS_WORD_FAULT_SHIFT) : 0u);
}

static void poll_inverter_status(dfp21b_t *c, hal_time_us_t now)
{
    if (!have_inverter(c) || !c->diag_alarm || c->status_poll_busy ||
        !hal_time_reached(now, c->next_status_poll)) {
        return;
    }
    const uint8_t req[ML_TELEGRAM_LEN] = {ML_MGMT_LENGTH_4 | ML_SVC_READ, 0x00,
                                          (uint8_t)(8310u >> 8), (uint8_t)(8310u & 0xFFu),
                                          0, 0, 0, 0};
    c->status_poll_busy = true;
    c->next_status_poll = now + DFP21B_STATUS_POLL_US;
    if (ml_client_request(&c->ml, DFP21B_CH_STATUS_POLL, req, on_status, c, now) != 0) {
        c->status_poll_busy = false;
    }
}

static void preempt(const dfp21b_t *c)
{
    if (c->cfg.preempt != NULL) {
        c->cfg.preempt(c->cfg.preempt_ctx);
    }
}

hal_time_us_t dfp21b_poll(dfp21b_t *c, hal_time_us_t now)
{
    if (!c->on_bus) {
        /* Off the bus the inverter still shows P093 (the manual's first diagnosis step for an
         * address above 125), so its monitor values are pushed once. */
        if (c->status_dirty) {
            push_fieldbus_status(c);
        }
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    c->now = now;
    hal_time_us_t next = dp_slave_poll(&c->dp, now);
    preempt(c);
    if (c->outputs_new) {
        c->outputs_new = false;
        take_outputs(c, now);
    }
    preempt(c);
    hal_time_us_t ml_next = ml_client_poll(&c->ml, now);
    next = hal_time_earlier(next, ml_next);
    preempt(c);
    hal_time_us_t v1_next = dpv1_poll(&c->dpv1, now);
    next = hal_time_earlier(next, v1_next);
    preempt(c);
    poll_inverter_status(c, now);
    if (have_inverter(c) && c->diag_alarm) {
        next = hal_time_earlier(next, c->next_status_poll);
    }
    if (c->status_dirty) {
        push_fieldbus_status(c);
    }
    preempt(c);
    if (c->inputs_dirty) {
        size_t len = build_inputs(c);
        preempt(c); /* framing the longest image is a section of its own */
        dp_slave_set_inputs(&c->dp, c->in_image, len);
        c->inputs_dirty = false;
    }
    preempt(c);
    dp_slave_prepare(&c->dp);
    update_leds(c);
    return next;
}

void dfp21b_set_inverter_fault(dfp21b_t *c, uint8_t fault)
{
    c->inverter_fault = fault;
    if (!c->diag_alarm || fault == 0u) {
        dp_slave_set_ext_diag(&c->dp, NULL, 0);
        return;
    }
    const uint8_t block[2] = {0x02u, fault}; /* device-related block, 2 octets incl. header */
    dp_slave_set_ext_diag(&c->dp, block, sizeof block);
}
