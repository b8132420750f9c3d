/* What a captured telegram is, for the replay check and its report: a lenient header parse
 * that also works on damaged records, the DP / DP-V1 service a request asks for, and one-line
 * descriptions of requests and answers ("Slave_Diag reply: Station_Not_Ready Prm_Req | no
 * master, ident 0x6003"). Pure functions, no allocation. */
#ifndef REPLAY_DECODE_H
#define REPLAY_DECODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum replay_kind {
    REPLAY_KIND_GARBAGE = 0, /* no header to speak of */
    REPLAY_KIND_SC,
    REPLAY_KIND_TOKEN,
    REPLAY_KIND_REQUEST,  /* SD1/SD2/SD3 with FC bit 6 set */
    REPLAY_KIND_RESPONSE, /* SD1/SD2/SD3 with FC bit 6 clear */
} replay_kind_t;

/* The header as far as the octets carry it. For a damaged record only what could be read is
 * filled in (has_header says whether DA, SA and FC were there). */
typedef struct replay_frame {
    replay_kind_t kind;
    bool has_header;
    uint8_t sd;
    uint8_t da; /* 7-bit */
    uint8_t sa;
    uint8_t fc;
    bool has_dsap;
    bool has_ssap;
    uint8_t dsap;
    uint8_t ssap;
    const uint8_t *du; /* data after the SAP octets */
    size_t du_len;
} replay_frame_t;

void replay_frame_parse(const uint8_t *f, size_t len, replay_frame_t *out);

/* The service of a request, counted separately in the check report. */
typedef enum replay_service {
    REPLAY_SVC_FDL_STATUS = 0,
    REPLAY_SVC_DATA_EXCHANGE,
    REPLAY_SVC_SET_PRM,
    REPLAY_SVC_CHK_CFG,
    REPLAY_SVC_SLAVE_DIAG,
    REPLAY_SVC_GET_CFG,
    REPLAY_SVC_GLOBAL_CONTROL,
    REPLAY_SVC_RD_INP,
    REPLAY_SVC_RD_OUTP,
    REPLAY_SVC_SET_SLAVE_ADD,
    REPLAY_SVC_SET_EXT_PRM,
    REPLAY_SVC_MSAC1_READ,
    REPLAY_SVC_MSAC1_WRITE,
    REPLAY_SVC_MSAC1_POLL,
    REPLAY_SVC_MSAC1_ALARM_ACK,
    REPLAY_SVC_MSAC1_OTHER,
    REPLAY_SVC_MSAC2_INITIATE,
    REPLAY_SVC_MSAC2_POLL,
    REPLAY_SVC_MSAC2_READ,
    REPLAY_SVC_MSAC2_WRITE,
    REPLAY_SVC_MSAC2_TRANSPORT,
    REPLAY_SVC_MSAC2_IDLE,
    REPLAY_SVC_MSAC2_ABORT,
    REPLAY_SVC_MSAC2_OTHER,
    REPLAY_SVC_ALARM_SAP,
    REPLAY_SVC_OTHER_SAP,
    REPLAY_SVC_OTHER_FUNCTION, /* SDA, Request Ident, LSAP status, time/counter events ... */
    REPLAY_SVC_COUNT
} replay_service_t;

replay_service_t replay_service_of(const replay_frame_t *req);
const char *replay_service_name(replay_service_t s);
/* True when the request's function asks for an answer (everything but SDN). */
bool replay_expects_answer(const replay_frame_t *req);

/* How Data_Exchange octets split, when the card's configuration is known: an 8-octet MOVILINK
 * channel first (param_channel), then PD words. known = false: plain hex. */
typedef struct replay_dx_layout {
    bool known;
    bool param_channel;
} replay_dx_layout_t;

/* One line about any telegram (request, answer, token, SC, garbage); out is always terminated.
 * lay may be NULL. */
size_t replay_describe(const uint8_t *f, size_t len, const replay_dx_layout_t *lay, char *out,
                       size_t max);
/* "68 05 05 68 ..." (at most max - 1 characters, "..." when cut). */
size_t replay_hex(const uint8_t *p, size_t len, char *out, size_t max);
/* "FDL_Status" for FC 0x49, "SRD high FCV=1 FCB=0" etc. */
size_t replay_fc_text(uint8_t fc, char *out, size_t max);

#endif
