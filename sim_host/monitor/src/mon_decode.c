#include "monitor/mon_decode.h"

#include <stdio.h>
#include <string.h>

#include "dfp21b/dfp21b.h"
#include "dp_slave/dp_wire.h"
#include "movidrive/movidrive_names.h"
#include "replay/param_text.h"
#include "rig/rig_log.h"
#include "sim_hal/text_buf.h"

/* Extended diagnosis block header (protocol.md §A3.4): type in bits 7..6, the block's length
 * including the header in bits 5..0. */
#define EXT_TYPE_SHIFT 6u
#define EXT_LEN_MASK 0x3Fu
#define EXT_DEVICE 0u
#define EXT_IDENTIFIER 1u
#define EXT_CHANNEL 2u
#define CHANNEL_BLOCK_LEN 3u
/* A DP-V1 alarm or status block: header, type, slot, specifier, data. */
#define DPV1_BLOCK_MIN 4u
#define DPV1_TYPE_STATUS 0x80u
#define SPEC_SEQ_SHIFT 3u
#define SPEC_ADD_ACK 0x04u
#define SPEC_KIND_MASK 0x03u
/* "0006 = ..." from movidrive_*_word_text: the monitor shows the word on its own. */
#define WORD_PREFIX_LEN 7u

static void put_hex(text_buf_t *b, const uint8_t *p, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        text_buf_put(b, i > 0u ? " %02X" : "%02X", p[i]);
    }
}

bool mon_prm_dpv1(const uint8_t *prm, size_t len)
{
    return len > DP_PRM_DPV1_STATUS_1 && (prm[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_ENABLE) != 0u;
}

/* ---- extended diagnosis ------------------------------------------------------------------- */

static void channel_block(text_buf_t *b, const uint8_t *p)
{
    static const char *const dirs[4] = {"", " input", " output", " input/output"};
    static const char *const types[8] = {"",      " bit",  " 2 bits",      " 4 bits",
                                         " byte", " word", " double word", " type 7"};
    static const char *const errors[10] = {NULL,       "short circuit",   "undervoltage",
                                           "overvoltage", "overload",     "overtemperature",
                                           "line break", "upper limit",   "lower limit",
                                           "error"};
    unsigned err = p[2] & 0x1Fu;
    text_buf_put(b, "channel: module %u channel %u%s%s, ", p[0] & EXT_LEN_MASK, p[1] & 0x3Fu,
        dirs[p[1] >> 6], types[p[2] >> 5]);
    if (err < 10u && errors[err] != NULL) {
        text_buf_put(b, "%s (%u)", errors[err], err);
    } else if (err >= 16u) {
        text_buf_put(b, "manufacturer error %u", err);
    } else {
        text_buf_put(b, "error %u", err);
    }
}

static void identifier_block(text_buf_t *b, const uint8_t *p, size_t len)
{
    text_buf_put(b, "identifier-related: modules");
    bool any = false;
    for (size_t i = 1; i < len; i++) {
        for (unsigned bit = 0; bit < 8u; bit++) {
            if (((p[i] >> bit) & 1u) != 0u) {
                text_buf_put(b, "%s %zu", any ? "," : "", (i - 1u) * 8u + bit);
                any = true;
            }
        }
    }
    if (!any) {
        text_buf_put(b, " none");
    }
}

static const char *alarm_name(uint8_t type)
{
    static const char *const names[7] = {NULL,     "diagnosis", "process", "pull",
                                         "plug", "status",    "update"};
    if (type < 7u && names[type] != NULL) {
        return names[type];
    }
    return type >= 32u && type <= 126u ? "manufacturer-specific" : "reserved";
}

static const char *status_name(uint8_t type)
{
    switch (type) {
    case 0x81u: return "Status_Message";
    case 0x82u: return "Module_Status";
    case 0x9Eu: return "PrmCmdAck";
    case 0x9Fu: return "Red_State";
    default: return "reserved status";
    }
}

static void dpv1_block(text_buf_t *b, const uint8_t *p, size_t len)
{
    static const char *const kinds[4] = {"", ", appears", ", disappears",
                                         ", disappears, slot still disturbed"};
    uint8_t spec = p[3];
    if ((p[1] & DPV1_TYPE_STATUS) != 0u) {
        text_buf_put(b, "%s (0x%02X), slot %u%s", status_name(p[1]), p[1], p[2],
            kinds[spec & SPEC_KIND_MASK]);
    } else {
        text_buf_put(b, "%s alarm (%u), slot %u, seq %u%s%s", alarm_name(p[1]), p[1], p[2],
            spec >> SPEC_SEQ_SHIFT, kinds[spec & SPEC_KIND_MASK],
            (spec & SPEC_ADD_ACK) != 0u ? ", Add_Ack" : "");
    }
    if (len > DPV1_BLOCK_MIN) {
        text_buf_put(b, ": ");
        put_hex(b, p + DPV1_BLOCK_MIN, len - DPV1_BLOCK_MIN);
    }
}

/* One block; returns its length, 0 when the header cannot be a block here (the rest is then
 * shown in hex). */
static size_t ext_block(text_buf_t *b, const uint8_t *p, size_t left, bool dpv1)
{
    unsigned type = p[0] >> EXT_TYPE_SHIFT;
    size_t len = p[0] & EXT_LEN_MASK;
    if (type == EXT_CHANNEL) {
        if (left < CHANNEL_BLOCK_LEN) {
            return 0;
        }
        channel_block(b, p);
        return CHANNEL_BLOCK_LEN;
    }
    if (len == 0u || len > left || type > EXT_CHANNEL) {
        return 0;
    }
    if (type == EXT_IDENTIFIER) {
        identifier_block(b, p, len);
    } else if (dpv1 && len >= DPV1_BLOCK_MIN) {
        dpv1_block(b, p, len);
    } else {
        text_buf_put(b, "device-related:");
        if (len == 1u) {
            text_buf_put(b, " empty");
        }
        for (size_t i = 1; i < len; i++) {
            text_buf_put(b, " %02X", p[i]);
        }
    }
    return len;
}

size_t mon_decode_diag(const uint8_t *d, size_t len, bool dpv1, char *out, size_t max)
{
    if (max == 0u) {
        return 0;
    }
    rig_diag_text(d, len < DP_DIAG_STD_LEN ? len : DP_DIAG_STD_LEN, out, max);
    text_buf_t b = {out, max, strlen(out)};
    if (len <= DP_DIAG_STD_LEN) {
        return b.n;
    }
    text_buf_put(&b, ", ext: ");
    size_t i = DP_DIAG_STD_LEN;
    while (i < len) {
        if (i > DP_DIAG_STD_LEN) {
            text_buf_put(&b, "; ");
        }
        size_t n = ext_block(&b, d + i, len - i, dpv1);
        if (n == 0u) {
            text_buf_put(&b, "bad block: ");
            put_hex(&b, d + i, len - i);
            break;
        }
        i += n;
    }
    return b.n;
}

/* ---- DFP21B ------------------------------------------------------------------------------- */

bool mon_is_dfp21b(const mon_station_t *st)
{
    return st->dp && st->ident_known && st->ident == DFP21B_IDENT;
}

static void word_text(int (*fn)(uint16_t, char *, size_t), uint16_t w, char *out, size_t max)
{
    char t[MON_DECODE_TEXT + WORD_PREFIX_LEN];
    fn(w, t, sizeof t);
    size_t n = strlen(t);
    const char *s = n >= WORD_PREFIX_LEN ? t + WORD_PREFIX_LEN : t;
    size_t len = strlen(s);
    if (max == 0u) {
        return;
    }
    len = len < max - 1u ? len : max - 1u;
    memcpy(out, s, len);
    out[len] = '\0';
}

void mon_decode_dfp21b(const uint8_t *cfg, size_t cfg_len, const uint8_t *outputs,
                       size_t out_len, const uint8_t *inputs, size_t in_len, mon_dfp21b_t *r)
{
    memset(r, 0, sizeof *r);
    dfp21b_pd_cfg_t pd;
    r->cfg_valid = dfp21b_check_cfg(cfg, cfg_len, &pd);
    r->param_channel = pd.param_channel;
    r->pd_words = pd.pd_words;
    dfp21b_p090_text(&pd, r->pd_config, sizeof r->pd_config);
    if (!r->cfg_valid) {
        return;
    }
    size_t first = pd.param_channel ? DFP21B_PARAM_LEN : 0u;
    if (out_len >= first + 2u) {
        r->has_control = true;
        r->control_word = (uint16_t)(outputs[first] << 8 | outputs[first + 1u]);
        word_text(movidrive_control_word_text, r->control_word, r->control_text,
                  sizeof r->control_text);
    }
    if (in_len >= first + 2u) {
        r->has_status = true;
        r->status_word = (uint16_t)(inputs[first] << 8 | inputs[first + 1u]);
        word_text(movidrive_status_word_text, r->status_word, r->status_text,
                  sizeof r->status_text);
    }
    if (pd.param_channel && out_len >= DFP21B_PARAM_LEN) {
        replay_channel_text(outputs, false, r->param_request, sizeof r->param_request);
    }
    if (pd.param_channel && in_len >= DFP21B_PARAM_LEN) {
        replay_channel_text(inputs, true, r->param_answer, sizeof r->param_answer);
    }
}

void mon_decode_dfp21b_station(const mon_station_t *st, mon_dfp21b_t *r)
{
    mon_decode_dfp21b(st->cfg, st->cfg_len, st->outputs, st->out_len, st->inputs, st->in_len, r);
}
