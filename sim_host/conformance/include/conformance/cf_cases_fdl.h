/* The GSD and FDL groups of the conformance suite (cases_gsd.c, cases_fdl.c), and the helpers
 * both groups share: a start-up the cases watch step by step (every diagnosis, any Set_Prm and
 * configuration, any module of the GSD) and telegrams built octet by octet. */
#ifndef CONFORMANCE_CF_CASES_FDL_H
#define CONFORMANCE_CF_CASES_FDL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "conformance/cf.h"

extern const cf_case_t cf_cases_gsd[];
extern const size_t cf_cases_gsd_count;
extern const cf_case_t cf_cases_fdl[];
extern const size_t cf_cases_fdl_count;

#define CF_GF_DU_MAX 244u
#define CF_GF_MAX_DIAGS 16u

/* What a start-up sends: a Set_Prm DU, a configuration and the I/O lengths it implies. */
typedef struct cf_gf_setup {
    uint8_t prm[CF_GF_DU_MAX];
    uint8_t prm_len;
    uint8_t cfg[CF_GF_DU_MAX];
    uint8_t cfg_len;
    uint16_t in_len, out_len;
    char name[64]; /* the module, for reasons */
} cf_gf_setup_t;

/* What a watched start-up saw. */
typedef struct cf_gf_trace {
    uint8_t n_diag;
    uint8_t diag_len[CF_GF_MAX_DIAGS];
    uint16_t ident[CF_GF_MAX_DIAGS];
    const char *step[CF_GF_MAX_DIAGS]; /* "in Wait_Prm", "after Set_Prm", ... */
    uint8_t last[CF_GF_DU_MAX];        /* the last diagnosis */
    uint8_t last_len;
    cf_reply_t dx;                     /* the answer to the start-up's Data_Exchange */
} cf_gf_trace_t;

/* The run's configured module, Set_Prm and lengths (cf->prm, cf->cfg, cf->in_len ...). */
void cf_gf_setup_default(const cf_t *cf, cf_gf_setup_t *s);
/* Module m of the GSD alone: cf->prm's standard octets and global user parameters, then the
 * module's own parameter part; its identifiers and lengths. False with the reason in why. */
bool cf_gf_setup_module(const cf_t *cf, size_t m, cf_gf_setup_t *s, char *why, size_t n);

/* Slave_Diag from the tester's master: true with the DU (at least 6 octets) when it came as a
 * DP diagnosis (SAPs 62/60 swapped back, DL or DH), else false with what came in why. */
bool cf_gf_diag(cf_t *cf, uint8_t *diag, size_t *len, char *why, size_t n);
/* The DUT answers SRD without data positively: SC, or SD1 with NR. */
bool cf_gf_ack(const cf_reply_t *r);
/* r answers a Data_Exchange of a slave with in_len inputs: DL/DH with in_len octets and no
 * SAPs (SC or SD1 without data when in_len is 0). */
bool cf_gf_dx_ok(const cf_t *cf, const cf_reply_t *r, uint16_t in_len, char *why, size_t n);
/* The diagnosis shows Data_Exch: no Station_Not_Ready, Cfg_Fault, Prm_Fault, Prm_Req. */
bool cf_gf_in_data_exch(const uint8_t *diag, size_t len);

/* Start-up with s: (reset,) Slave_Diag, Set_Prm, Slave_Diag, Chk_Cfg, Slave_Diag until ready,
 * one Data_Exchange with zero outputs. Every diagnosis goes into t (may be NULL). False with
 * the step that went wrong in why (the case has failed already when the link failed). */
bool cf_gf_bring_up(cf_t *cf, const cf_gf_setup_t *s, bool reset, cf_gf_trace_t *t, char *why,
                    size_t n);

/* "68 05 05 68 ..." (cut with "..." when buf is short). */
const char *cf_gf_hex(const uint8_t *p, size_t len, char *buf, size_t cap);

/* FCB/FCV of requests built octet by octet, as a master keeps them for one responder: the
 * first FCV=0 FCB=1, then FCV=1 with FCB toggling. */
typedef struct cf_gf_fcb {
    bool started;
    bool fcb;
} cf_gf_fcb_t;
uint8_t cf_gf_next_fc(cf_gf_fcb_t *s, uint8_t code);
/* A request FC with FCV and FCB as given. */
uint8_t cf_gf_fc(uint8_t code, bool fcv, bool fcb);

#endif
