/* What the DP-V1 cases share (cases_dpv1.c, cases_dpv1_c2.c, cases_dpv1_util.c): one DP-V1
 * request/response exchange at FDL level, and the MSAC2 connection a case opens and closes.
 *
 * The exchange, as the DP-V1 services run on layer 2 (protocol.md §A4.3, §A4.4): the request PDU
 * goes in an SRD to the service's SAP; the slave takes it (SC, or a no-data answer) and the
 * master polls with SRDs without data to the same SAPs until the response PDU comes as data with
 * the SAPs swapped. A slave that has the response at once may send it to the request itself:
 * that is taken as the response too. Library-private: not part of the contract (cf.h). */
#ifndef CONFORMANCE_CASES_DPV1_INTERNAL_H
#define CONFORMANCE_CASES_DPV1_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "conformance/cf.h"

/* The SSAP of the suite's class-2 master (any SAP is allowed; 50 is what class-2 tools use). */
#define V1_C2_SSAP 50u
/* How long a response may take where the GSD gives no C1/C2_Response_Timeout (1 s). */
#define V1_RESPONSE_TIMEOUT_DEFAULT_MS 1000u
/* The most MSAC2 connections a case opens (a GSD may claim more; the cases need C_Max + 1). */
#define V1_MAX_CONNS 8u

typedef enum v1_status {
    V1_RESPONSE = 0, /* a response PDU (positive, negative or an Abort) is in the result */
    V1_REFUSED,      /* the FDL refused the request: RS, RR, UE ... (fdl_code) */
    V1_SILENT,       /* no answer to the request at all */
    V1_TIMEOUT,      /* the request was taken, no response came within the time */
    V1_BROKEN,       /* the case has failed already (link, malformed answer) */
} v1_status_t;

/* Where a request goes: from master sa (and its ssap) to the DUT's dsap. */
typedef struct v1_path {
    uint8_t sa;
    uint8_t dsap;
    uint8_t ssap;
} v1_path_t;

typedef struct v1_result {
    uint8_t pdu[CF_FRAME_MAX];
    size_t len;
    int fdl_code;      /* V1_REFUSED: the FDL response code (FDL_RSP_*) */
    uint32_t polls;    /* empty SRDs sent after the request */
} v1_result_t;

/* Sends the request PDU (len 0: polls only, the request reached the slave another way) and
 * polls until the response or timeout_ms. V1_BROKEN when the case has failed (the reason is
 * set: the link failed, the answer was garbled or carried the wrong SAPs). */
v1_status_t v1_call(cf_t *cf, const v1_path_t *p, const uint8_t *pdu, size_t len,
                    uint32_t timeout_ms, v1_result_t *out);
/* The same, then Read.req of the same index while the answer is the negative "state conflict"
 * (B5: the application is still working, protocol.md §A4.3), bounded by timeout_ms. */
v1_status_t v1_write_read(cf_t *cf, const v1_path_t *p, const uint8_t *wpdu, size_t wlen,
                          uint32_t timeout_ms, v1_result_t *wres, v1_result_t *rres);

/* "RS", "RR" ... for an FDL response code. */
const char *v1_fdl_code_name(int code);
/* A PDU as text for a reason: "DE 80 B0 00" (at most the first 12 octets). */
const char *v1_hex(const uint8_t *p, size_t n, char *buf, size_t cap);
/* True when the PDU is a DP-V1 negative response to function fn: fn|80, Error_Decode 0x80,
 * 4 octets; *code1 gets Error_Code_1. */
bool v1_negative(const uint8_t *pdu, size_t len, uint8_t fn, uint8_t *code1);
/* "invalid index" ... for Error_Code_1 (protocol.md §A4.2). */
const char *v1_error_name(uint8_t code1);
/* Fails the case unless status is V1_RESPONSE, saying what came instead of a response to the
 * named request; returns status == V1_RESPONSE. */
bool v1_need_response(cf_t *cf, v1_status_t st, const v1_result_t *r, const char *what);

/* A GSD key's value (0 when absent). */
uint32_t v1_key(const cf_t *cf, gsd_key_t k);
/* The link's time in ms. */
uint64_t v1_now_ms(const cf_t *cf);
/* C1_Response_Timeout / C2_Response_Timeout of the GSD in ms (10 ms units), or the default. */
uint32_t v1_c1_timeout_ms(const cf_t *cf);
uint32_t v1_c2_timeout_ms(const cf_t *cf);

/* ---- MSAC1 -------------------------------------------------------------------------------- */

/* NA (false) unless the GSD claims DPV1_Slave and C1_Read_Write_supp; then the DUT is brought to
 * Data_Exch with the DP-V1 Set_Prm (false: the case has failed). */
bool v1_c1_ready(cf_t *cf);
v1_path_t v1_c1_path(const cf_t *cf);

/* ---- MSAC2 -------------------------------------------------------------------------------- */

typedef struct v1_conn {
    bool open;
    uint8_t sa;    /* the class-2 master's address */
    uint8_t ssap;
    uint8_t sap;   /* the connection's SAP the resource manager named */
    uint8_t res[CF_FRAME_MAX]; /* the Initiate.res, or the refusal (an Abort PDU ...) */
    size_t res_len;
} v1_conn_t;

typedef enum v1_open {
    V1_OPENED = 0,  /* Initiate.res came: conn->open */
    V1_ABORTED,     /* an Abort PDU came instead (from the resource manager or the SAP) */
    V1_NEGATIVE,    /* a negative Initiate (D7 ...) */
    V1_NOT_OPENED,  /* the FDL refused, silence or no answer in time (the reason is in why) */
    V1_OPEN_BROKEN, /* the case has failed (link, malformed answer) */
} v1_open_t;

/* NA (false) unless the GSD claims DPV1_Slave and C2_Read_Write_supp. */
bool v1_c2_claimed(cf_t *cf);
/* C2_Max_Count_Channels (at least 1 when C2 is claimed), at most V1_MAX_CONNS - 1. */
unsigned v1_c2_channels(const cf_t *cf);
/* The address of the i-th class-2 master the cases use: opt.class2 first, then free addresses
 * that are neither the DUT nor one of the tester's masters. */
uint8_t v1_c2_master(const cf_t *cf, unsigned i);
/* Initiate.req with send_timeout (10 ms units) from master sa, SSAP V1_C2_SSAP; the resource
 * manager's answer checked against the standard's form (56 SAP TO TO with SAP 0..48). why gets
 * a text for V1_NOT_OPENED. */
v1_open_t v1_c2_open(cf_t *cf, uint8_t sa, uint16_t send_timeout, v1_conn_t *c, char *why,
                     size_t why_len);
/* Abort.req (58 00 user|0 00) on the connection; it is closed whatever the answer. False only
 * when the link failed. */
bool v1_c2_abort(cf_t *cf, v1_conn_t *c);
/* Aborts every open connection of the array (a case's clean-up, whatever its verdict). */
void v1_c2_close_all(cf_t *cf, v1_conn_t *c, size_t n);
v1_path_t v1_conn_path(const v1_conn_t *c);

/* A Read.req of slot 0, index 255 (length 240) as a request every DP-V1 slave answers with a
 * Read response (the data or a negative one): it shows a connection serves. */
size_t v1_probe_read(uint8_t *pdu);
/* The PDU is a Read response (5E or DE) of the probe's slot and index. */
bool v1_is_read_response(const uint8_t *pdu, size_t len);

/* ---- the MSAC2 cases (cases_dpv1_c2.c), joined into the group's table -------------------- */

void v1_case_c2_initiate(cf_t *cf);
void v1_case_c2_abort(cf_t *cf);
void v1_case_c2_idle_timeout(cf_t *cf);
void v1_case_c2_two_connections(cf_t *cf);
void v1_case_c2_third_refused(cf_t *cf);

#define V1_STD_C2 "IEC 61158-6-3 MSAC_C2 resource manager and connection (protocol.md §A4.4)"
#define V1_C2_CASES                                                                             \
    { "dpv1.msac2.initiate", "DP-V1", V1_STD_C2,                                                \
      "Initiate on SAP 49: the RM names a SAP 0..48, Initiate.res with DPV1_RW; it serves",     \
      v1_case_c2_initiate },                                                                    \
    { "dpv1.msac2.abort", "DP-V1", V1_STD_C2,                                                   \
      "after Abort the SAP no longer serves the master and the resource is free again",         \
      v1_case_c2_abort },                                                                       \
    { "dpv1.msac2.idle_timeout", "DP-V1", V1_STD_C2,                                            \
      "kept within Send_Timeout the connection lives; silent beyond it, it is closed",          \
      v1_case_c2_idle_timeout },                                                                \
    { "dpv1.msac2.two_connections", "DP-V1", V1_STD_C2,                                         \
      "two masters hold a connection each on its own SAP, bound to its master",                 \
      v1_case_c2_two_connections },                                                             \
    { "dpv1.msac2.third_refused", "DP-V1", V1_STD_C2,                                           \
      "an Initiate beyond C2_Max_Count_Channels refused with Abort (reason RES)",              \
      v1_case_c2_third_refused }

#endif
