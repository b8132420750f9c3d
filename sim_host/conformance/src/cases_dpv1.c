/* The "DP-V1" group, MSAC1, data set 47 and I&M (the MSAC2 cases are in cases_dpv1_c2.c): what
 * IEC 61158-6-3's acyclic services and the PROFIdrive / I&M profiles ask of a slave whose GSD
 * claims them (docs/protocol.md §A4, §A5, §A7). Every expectation is the standard's; a feature
 * the GSD does not claim is NOT APPLICABLE. */
#include <stdio.h>
#include <string.h>

#include "cases_dpv1_internal.h"
#include "conformance/cf_cases_v1t.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "dpv1/dpv1_wire.h"

/* A slot beyond any configuration (244 modules at most) and an index no profile gives a data
 * set: what a conforming slave has to refuse. */
#define V1_NO_SLOT 254u
#define V1_NO_INDEX 253u
/* PROFIdrive P965, the profile number (Octet String 2), of the base-mode parameter access. */
#define PD_PNU_PROFILE 965u

/* The acyclic path a record case uses: MSAC1 in Data_Exch, or an MSAC2 connection. */
typedef struct v1_chan {
    v1_path_t p;
    v1_conn_t conn;
    uint32_t timeout_ms;
} v1_chan_t;

static bool chan_open(cf_t *cf, v1_chan_t *ch, bool prefer_c2)
{
    char why[96];
    memset(ch, 0, sizeof *ch);
    if (!cf->dpv1) {
        return cf_na(cf, "the GSD does not claim DPV1_Slave");
    }
    bool c1 = v1_key(cf, GSD_K_C1_READ_WRITE_SUPP) != 0u;
    bool c2 = v1_key(cf, GSD_K_C2_READ_WRITE_SUPP) != 0u;
    if (!c1 && !c2) {
        return cf_na(cf, "the GSD claims neither C1_Read_Write_supp nor C2_Read_Write_supp");
    }
    if (c2 && (prefer_c2 || !c1)) {
        ch->timeout_ms = v1_c2_timeout_ms(cf);
        v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, 0), 300u, &ch->conn, why, sizeof why);
        if (o == V1_OPENED) {
            ch->p = v1_conn_path(&ch->conn);
            return true;
        }
        return o == V1_OPEN_BROKEN ? false
                                   : cf_fail(cf, "MSAC2 Initiate not accepted: %s",
                                             o == V1_NOT_OPENED ? why : "refused");
    }
    ch->timeout_ms = v1_c1_timeout_ms(cf);
    ch->p = v1_c1_path(cf);
    return v1_c1_ready(cf);
}

static void chan_close(cf_t *cf, v1_chan_t *ch)
{
    v1_c2_close_all(cf, &ch->conn, 1);
}

/* The response must be these octets exactly. */
static bool expect_pdu(cf_t *cf, const v1_result_t *r, const uint8_t *want, size_t n,
                       const char *what)
{
    char w[64], g[64];
    return cf_check(cf, r->len == n && memcmp(r->pdu, want, n) == 0, "%s: expected %s, got %s",
                    what, v1_hex(want, n, w, sizeof w), v1_hex(r->pdu, r->len, g, sizeof g));
}

/* A negative response to fn with Error_Code_1 one of codes (n of them); the code seen goes to
 * the information. */
static bool expect_negative(cf_t *cf, const v1_result_t *r, uint8_t fn, const uint8_t *codes,
                            size_t n, const char *what)
{
    char g[64];
    uint8_t code1 = 0;
    bool neg = v1_negative(r->pdu, r->len, fn, &code1);
    bool listed = false;
    for (size_t i = 0; neg && i < n; i++) {
        listed = listed || codes[i] == code1;
    }
    if (!listed) {
        return cf_fail(cf, "%s: expected %02X 80 %02X xx (%s)%s, got %s", what,
                       (unsigned)(fn | DPV1_FN_ERROR), codes[0], v1_error_name(codes[0]),
                       n > 1u ? " or another code of the list" : "",
                       v1_hex(r->pdu, r->len, g, sizeof g));
    }
    cf_info(cf, "%s: %02X 80 %02X (%s)", what, r->pdu[0], code1, v1_error_name(code1));
    return true;
}

/* ---- I&M through the call service --------------------------------------------------------- */

/* Selects I&M0 (Write 255 "08 00 FD E8") and reads it: the 64-octet record in rec. */
static bool im0_read(cf_t *cf, const v1_chan_t *ch, uint8_t *rec)
{
    const uint8_t w[] = { DPV1_FN_WRITE, 0, DPV1_INDEX_IM, IM_CALL_HEADER_LEN,
                          IM_FN_CALL, 0, IM_INDEX_0 >> 8, IM_INDEX_0 & 0xFFu };
    const uint8_t wres[] = { DPV1_FN_WRITE, 0, DPV1_INDEX_IM, IM_CALL_HEADER_LEN };
    v1_result_t wr, rr;
    memset(&rr, 0, sizeof rr);
    v1_status_t st = v1_write_read(cf, &ch->p, w, sizeof w, ch->timeout_ms, &wr, &rr);
    if (wr.len == 0u || rr.len == 0u) {
        return v1_need_response(cf, st, wr.len == 0u ? &wr : &rr,
                                wr.len == 0u ? "Write.req index 255" : "Read.req index 255");
    }
    if (!expect_pdu(cf, &wr, wres, sizeof wres, "Write.req of the I&M0 call header")) {
        return false;
    }
    const uint8_t head[] = { DPV1_FN_READ, 0, DPV1_INDEX_IM, IM_CALL_HEADER_LEN + IM_RECORD_LEN,
                             IM_FN_CALL, 0, IM_INDEX_0 >> 8, IM_INDEX_0 & 0xFFu };
    const size_t whole = DPV1_HEADER_LEN + IM_CALL_HEADER_LEN + IM_RECORD_LEN;
    char g[64];
    if (!cf_check(cf, rr.len == whole && memcmp(rr.pdu, head, sizeof head) == 0,
                  "Read.req index 255 after selecting I&M0: expected %zu octets 5E 00 FF 44 "
                  "08 00 FD E8 + the record, got %zu: %s", whole, rr.len,
                  v1_hex(rr.pdu, rr.len, g, sizeof g))) {
        return false;
    }
    memcpy(rec, &rr.pdu[sizeof head], IM_RECORD_LEN);
    return true;
}

static bool visible(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (p[i] < 0x20u || p[i] > 0x7Eu) {
            return false;
        }
    }
    return true;
}

static uint16_t be16(const uint8_t *p)
{
    return (uint16_t)((unsigned)p[0] << 8 | p[1]);
}

/* The I&M0 fields (protocol.md §A7 layout) against the I&M profile's types. */
static void im0_judge(cf_t *cf, const uint8_t *rec)
{
    const uint8_t *order = &rec[12], *serial = &rec[32], *sw = &rec[50], *ver = &rec[60];
    if (!cf_check(cf, visible(order, IM0_ORDER_ID_LEN), "ORDER_ID: expected 20 visible "
                  "characters (blank padded), got a non-printable octet") ||
        !cf_check(cf, visible(serial, IM0_SERIAL_LEN), "SERIAL_NUMBER: expected 16 visible "
                  "characters, got a non-printable octet") ||
        !cf_check(cf, memchr("VRPUT", sw[0], 5) != NULL && sw[0] != 0u,
                  "SOFTWARE_REVISION: expected the prefix V, R, P, U or T, got 0x%02X", sw[0]) ||
        !cf_check(cf, ver[0] == IM0_VERSION_MAJOR, "IM_VERSION: expected major version 1, "
                  "got %u.%u", ver[0], ver[1])) {
        return;
    }
    cf_info(cf, "MANUFACTURER_ID 0x%04X, ORDER_ID \"%.20s\", SOFTWARE_REVISION %c%u.%u.%u, "
            "REV_COUNTER %u, PROFILE_ID 0x%04X, IM_VERSION %u.%u, IM_SUPPORTED 0x%04X",
            be16(&rec[10]), (const char *)order, sw[0], sw[1], sw[2], sw[3], be16(&rec[54]),
            be16(&rec[56]), ver[0], ver[1], be16(&rec[62]));
}

/* I&M0 is read only (I&M profile): writing it back is refused with a negative Write.res. */
static void im0_write_refused(cf_t *cf, const v1_chan_t *ch, const uint8_t *rec)
{
    uint8_t w[DPV1_HEADER_LEN + IM_CALL_HEADER_LEN + IM_RECORD_LEN] = {
        DPV1_FN_WRITE, 0, DPV1_INDEX_IM, IM_CALL_HEADER_LEN + IM_RECORD_LEN,
        IM_FN_CALL, 0, IM_INDEX_0 >> 8, IM_INDEX_0 & 0xFFu };
    memcpy(&w[DPV1_HEADER_LEN + IM_CALL_HEADER_LEN], rec, IM_RECORD_LEN);
    v1_result_t r;
    uint8_t code1;
    char g[64];
    v1_status_t st = v1_call(cf, &ch->p, w, sizeof w, ch->timeout_ms, &r);
    if (!v1_need_response(cf, st, &r, "Write.req of I&M0")) {
        return;
    }
    if (cf_check(cf, v1_negative(r.pdu, r.len, DPV1_FN_WRITE, &code1),
                 "writing I&M0 (read only): expected a negative Write.res DF 80 xx xx, got %s",
                 v1_hex(r.pdu, r.len, g, sizeof g))) {
        cf_info(cf, "I&M0 write refused with %02X (%s)", code1, v1_error_name(code1));
    }
}

static void case_im0(cf_t *cf)
{
    if (v1_key(cf, GSD_K_IDENT_MAINTENANCE_SUPP) == 0u) {
        return (void)cf_na(cf, "the GSD does not claim Ident_Maintenance_supp");
    }
    v1_chan_t ch;
    uint8_t rec[IM_RECORD_LEN], again[IM_RECORD_LEN];
    if (!chan_open(cf, &ch, true)) {
        return;
    }
    if (im0_read(cf, &ch, rec)) {
        im0_judge(cf, rec);
    }
    if (!cf_decided(cf) && im0_read(cf, &ch, again)) {
        (void)cf_check(cf, memcmp(rec, again, sizeof rec) == 0, "I&M0 read twice with nothing "
                       "written between: expected the same record, got another (REV_COUNTER "
                       "%u then %u)", be16(&rec[54]), be16(&again[54]));
    }
    if (!cf_decided(cf)) {
        im0_write_refused(cf, &ch, rec);
    }
    chan_close(cf, &ch);
}

/* ---- MSAC1 -------------------------------------------------------------------------------- */

static void case_c1_read_write(cf_t *cf)
{
    v1_chan_t ch;
    uint8_t rec[IM_RECORD_LEN];
    if (!cf->dpv1 || v1_key(cf, GSD_K_C1_READ_WRITE_SUPP) == 0u) {
        return (void)cf_na(cf, "the GSD does not claim DPV1_Slave with C1_Read_Write_supp");
    }
    if (v1_key(cf, GSD_K_IDENT_MAINTENANCE_SUPP) == 0u) {
        return (void)cf_na(cf, "no data set of this slave is known to the suite: the GSD does "
                           "not claim Ident_Maintenance_supp (I&M, index 255)");
    }
    if (chan_open(cf, &ch, false) && im0_read(cf, &ch, rec)) {
        cf_info(cf, "Write and Read of index 255 (I&M0 call) on MSAC1");
    }
}

/* One request that must be refused with one of codes. NA-worthy positive answers: *positive. */
static bool refused(cf_t *cf, const v1_path_t *p, const uint8_t *pdu, size_t len,
                    const uint8_t *codes, size_t n, const char *what, bool *positive)
{
    v1_result_t r;
    v1_status_t st = v1_call(cf, p, pdu, len, v1_c1_timeout_ms(cf), &r);
    if (!v1_need_response(cf, st, &r, what)) {
        return false;
    }
    *positive = r.len > 0u && r.pdu[0] == pdu[0];
    return *positive || expect_negative(cf, &r, pdu[0], codes, n, what);
}

static void case_c1_bad_slot(cf_t *cf)
{
    const uint8_t rd[] = { DPV1_FN_READ, V1_NO_SLOT, V1_NO_INDEX, DPV1_MAX_DATA };
    const uint8_t wr[] = { DPV1_FN_WRITE, V1_NO_SLOT, V1_NO_INDEX, 2, 0, 0 };
    /* Invalid slot; a slave may look at the index first and find none there (invalid index). */
    const uint8_t codes[] = { 0xB2u, DPV1_ERR_INVALID_INDEX };
    bool pos = false;
    if (!v1_c1_ready(cf)) {
        return;
    }
    v1_path_t p = v1_c1_path(cf);
    if (refused(cf, &p, rd, sizeof rd, codes, 2, "Read.req slot 254", &pos) && !pos &&
        refused(cf, &p, wr, sizeof wr, codes, 2, "Write.req slot 254", &pos) && !pos) {
        return;
    }
    (void)(pos && cf_fail(cf, "slot 254 lies beyond any configuration: expected invalid slot "
                          "(B2) or invalid index (B0), got a positive response"));
}

static void case_c1_bad_index(cf_t *cf)
{
    const uint8_t rd[] = { DPV1_FN_READ, 0, V1_NO_INDEX, DPV1_MAX_DATA };
    const uint8_t wr[] = { DPV1_FN_WRITE, 0, V1_NO_INDEX, 2, 0, 0 };
    const uint8_t codes[] = { DPV1_ERR_INVALID_INDEX };
    bool pos = false;
    if (!v1_c1_ready(cf)) {
        return;
    }
    v1_path_t p = v1_c1_path(cf);
    if (refused(cf, &p, rd, sizeof rd, codes, 1, "Read.req slot 0 index 253", &pos) && !pos &&
        refused(cf, &p, wr, sizeof wr, codes, 1, "Write.req slot 0 index 253", &pos) && !pos) {
        return;
    }
    (void)(pos && cf_na(cf, "the slave has a data set at slot 0 index 253: no index is known "
                        "to be absent"));
}

static void case_c1_bad_length(cf_t *cf)
{
    /* The Length octet says 8 where 4 data octets follow: a write length error. */
    const uint8_t wr[] = { DPV1_FN_WRITE, 0, DPV1_INDEX_IM, 8, IM_FN_CALL, 0,
                           IM_INDEX_0 >> 8, IM_INDEX_0 & 0xFFu };
    const uint8_t wcodes[] = { DPV1_ERR_WRITE_LENGTH };
    /* Read Length 0 (the standard's range is 1..240): an access error, coded by the slave as
     * write length, type conflict (the VPC3's choice), invalid range or invalid parameter. */
    const uint8_t rd[] = { DPV1_FN_READ, 0, DPV1_INDEX_IM, 0 };
    const uint8_t rcodes[] = { DPV1_ERR_INVALID_RANGE, DPV1_ERR_WRITE_LENGTH, 0xB3u, 0xB8u };
    bool pos = false;
    if (v1_key(cf, GSD_K_IDENT_MAINTENANCE_SUPP) == 0u && cf->dpv1) {
        return (void)cf_na(cf, "no index of this slave is known to the suite: the GSD does not "
                           "claim Ident_Maintenance_supp (I&M, index 255)");
    }
    if (!v1_c1_ready(cf)) {
        return;
    }
    v1_path_t p = v1_c1_path(cf);
    if (refused(cf, &p, wr, sizeof wr, wcodes, 1, "Write.req length 8 with 4 octets", &pos) &&
        !pos && refused(cf, &p, rd, sizeof rd, rcodes, 4, "Read.req length 0", &pos) && !pos) {
        return;
    }
    (void)(pos && cf_fail(cf, "a length outside the request: expected a negative response, "
                          "got a positive one"));
}

static void case_c1_not_enabled(cf_t *cf)
{
    if (!cf->dpv1 || v1_key(cf, GSD_K_C1_READ_WRITE_SUPP) == 0u) {
        return (void)cf_na(cf, "the GSD does not claim DPV1_Slave with C1_Read_Write_supp");
    }
    if (cf->prm_len < DP_PRM_LEN_DPV1) {
        return (void)cf_fail(cf, "the start-up Set_Prm has no DPV1_Status octets");
    }
    uint8_t saved = cf->prm[DP_PRM_DPV1_STATUS_1];
    cf->prm[DP_PRM_DPV1_STATUS_1] = (uint8_t)(saved & ~DP_DPV1_1_ENABLE);
    bool up = cf_start_up(cf);
    cf->prm[DP_PRM_DPV1_STATUS_1] = saved;
    if (!up) {
        return;
    }
    uint8_t pdu[DPV1_HEADER_LEN];
    v1_result_t r;
    v1_path_t p = v1_c1_path(cf);
    char g[64];
    v1_status_t st = v1_call(cf, &p, pdu, v1_probe_read(pdu), v1_c1_timeout_ms(cf), &r);
    if (st == V1_REFUSED && r.fdl_code == FDL_RSP_RS) {
        return;
    }
    if (st != V1_BROKEN) {
        const char *got = st == V1_SILENT    ? "silence"
                          : st == V1_REFUSED ? v1_fdl_code_name(r.fdl_code)
                          : st == V1_TIMEOUT ? "the request taken (SC)"
                                             : v1_hex(r.pdu, r.len, g, sizeof g);
        (void)cf_fail(cf, "MSAC1 in Data_Exch without DPV1_Enable: expected RS (SAP 51 not "
                      "activated), got %s", got);
    }
}

/* ---- data set 47, PROFIdrive base mode ---------------------------------------------------- */

/* Octets of one value of a PROFIdrive format (protocol.md §A5.2); 0 for an unknown format. */
static size_t pd_value_size(uint8_t format)
{
    switch (format) {
    case DS47_FORMAT_BOOLEAN: case DS47_FORMAT_INTEGER8: case DS47_FORMAT_UNSIGNED8:
    case DS47_FORMAT_VISIBLE_STRING: case DS47_FORMAT_OCTET_STRING: case DS47_FORMAT_BYTE:
        return 1;
    case DS47_FORMAT_INTEGER16: case DS47_FORMAT_UNSIGNED16: case DS47_FORMAT_WORD:
    case DS47_FORMAT_ERROR:
        return 2;
    case DS47_FORMAT_INTEGER32: case DS47_FORMAT_UNSIGNED32: case DS47_FORMAT_FLOAT:
    case DS47_FORMAT_DWORD:
        return 4;
    default:
        return 0;
    }
}

/* The base-mode response to "ref 01, request, axis 0, one parameter P965" (protocol.md §A5.2):
 * header echoed, one value block (or an error block when the id says negative). */
static void pd_judge(cf_t *cf, const uint8_t *d, size_t n)
{
    char g[64];
    if (!cf_check(cf, n >= DS47_HEADER_LEN + DS47_VALUE_HEADER_LEN && d[0] == 0x01u &&
                  (d[1] == DS47_ID_REQUEST || d[1] == (DS47_ID_REQUEST | DS47_ID_ERROR)) &&
                  d[2] == 0u && d[3] == 1u, "data set 47 response: expected 01 01|81 00 01 "
                  "(reference, id, axis, one parameter) and a block, got %s",
                  v1_hex(d, n, g, sizeof g))) {
        return;
    }
    bool negative = d[1] != DS47_ID_REQUEST;
    uint8_t format = d[4], count = d[5];
    size_t size = pd_value_size(format), body = size * count, expect = 6u + body + (body & 1u);
    if (!cf_check(cf, negative == (format == DS47_FORMAT_ERROR) && size > 0u && count > 0u &&
                  (n == expect || n == 6u + body), "data set 47 response: a %s response "
                  "needs a %s block of known format and its values, got %s",
                  negative ? "negative" : "positive", negative ? "44 (error)" : "value",
                  v1_hex(d, n, g, sizeof g))) {
        return;
    }
    if (negative) {
        cf_info(cf, "P965 refused with PROFIdrive error 0x%04X", be16(&d[6]));
    } else {
        cf_info(cf, "P965 format 0x%02X, %u values: %s", format, count,
                v1_hex(&d[6], body, g, sizeof g));
    }
}

static void case_ds47(cf_t *cf)
{
    const uint8_t w[] = { DPV1_FN_WRITE, 0, DPV1_INDEX_DS47, 10, 0x01, DS47_ID_REQUEST, 0, 1,
                          DS47_ATTR_VALUE, 0, PD_PNU_PROFILE >> 8, PD_PNU_PROFILE & 0xFFu, 0, 0 };
    const uint8_t wres[] = { DPV1_FN_WRITE, 0, DPV1_INDEX_DS47, 10 };
    v1_chan_t ch;
    v1_result_t wr, rr;
    uint8_t code1 = 0;
    char g[64];
    memset(&rr, 0, sizeof rr);
    if (!chan_open(cf, &ch, false)) {
        return;
    }
    v1_status_t st = v1_write_read(cf, &ch.p, w, sizeof w, ch.timeout_ms, &wr, &rr);
    if (wr.len > 0u && v1_negative(wr.pdu, wr.len, DPV1_FN_WRITE, &code1) &&
        code1 == DPV1_ERR_INVALID_INDEX) {
        cf_na(cf, "the slave refuses index 47 (invalid index): no PROFIdrive base mode");
    } else if (wr.len == 0u || rr.len == 0u) {
        (void)v1_need_response(cf, st, wr.len == 0u ? &wr : &rr,
                               wr.len == 0u ? "Write.req index 47" : "Read.req index 47");
    } else if (expect_pdu(cf, &wr, wres, sizeof wres, "Write.req of the parameter request") &&
               cf_check(cf, rr.len > DPV1_HEADER_LEN && rr.pdu[0] == DPV1_FN_READ &&
                        rr.pdu[2] == DPV1_INDEX_DS47 && rr.pdu[3] == rr.len - DPV1_HEADER_LEN,
                        "Read.req index 47: expected 5E 00 2F n + n octets, got %s",
                        v1_hex(rr.pdu, rr.len, g, sizeof g))) {
        pd_judge(cf, &rr.pdu[DPV1_HEADER_LEN], rr.len - DPV1_HEADER_LEN);
    }
    chan_close(cf, &ch);
}

/* ---- the group's table -------------------------------------------------------------------- */

#define STD_C1 "IEC 61158-6-3 MSAC_C1 Read/Write and DP-V1 error PDU (protocol.md §A4.2, §A4.3)"

const cf_case_t cf_cases_dpv1[] = {
    { "dpv1.msac1.read_write", "DP-V1", STD_C1,
      "a Write and a Read of a data set on MSAC1 (the I&M0 call) answer as the PDUs say",
      case_c1_read_write },
    { "dpv1.msac1.bad_slot", "DP-V1", STD_C1,
      "Read/Write of slot 254 answered DE/DF 80 B2 (invalid slot) or B0", case_c1_bad_slot },
    { "dpv1.msac1.bad_index", "DP-V1", STD_C1,
      "Read/Write of an index the slave lacks answered DE/DF 80 B0 (invalid index)",
      case_c1_bad_index },
    { "dpv1.msac1.bad_length", "DP-V1", STD_C1,
      "a Write whose Length disagrees answered DF 80 B1; a Read of Length 0 refused",
      case_c1_bad_length },
    { "dpv1.msac1.not_enabled", "DP-V1",
      "IEC 61158-6-3 MSAC_C1 activation by Set_Prm DPV1_Status_1 (protocol.md §A3.2, §A4.3)",
      "without DPV1_Enable in Set_Prm, SAP 51 is not activated: RS", case_c1_not_enabled },
    V1_C2_CASES,
    { "dpv1.ds47.profidrive", "DP-V1",
      "PROFIdrive base mode parameter access, data set 47 (protocol.md §A5.1, §A5.2)",
      "a parameter request (P965) on index 47 answered in the base-mode response layout",
      case_ds47 },
    { "dpv1.im0", "DP-V1", "PROFIBUS I&M profile: I&M0 via the call service, index 255 "
      "(protocol.md §A7)", "I&M0 read: 64 octets, visible texts, IM_VERSION 1.x, read only",
      case_im0 },
};
const size_t cf_cases_dpv1_count = sizeof cf_cases_dpv1 / sizeof cf_cases_dpv1[0];
