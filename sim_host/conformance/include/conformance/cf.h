/* An open conformance suite for PROFIBUS-DP slaves: a test master that takes a device under
 * test (the DUT: a slave at one address on a line the tester holds alone), runs test cases
 * grouped like the PI DP slave test specification (order no. 2.032) and gives each a verdict
 * with the clause it checks and the telegrams that decided it.
 *
 * The suite knows the DUT only through its GSD file and the wire: every expectation is derived
 * from the standard (IEC 61158-6-3 / EN 50170 vol. 2, IEC 61784-1 CP 3/1, the GSD
 * specification), never from this project's card. docs/conformance.md lists the cases.
 *
 * A case is a function that talks to the DUT with cf_exchange / cf_dp / the start-up helpers,
 * checks what came back with cf_check / cf_fail / cf_na, and returns. Every telegram sent and
 * received is kept as evidence of the case (the last CF_MAX_EVIDENCE of them). A case starts
 * from whatever state the previous one left: it brings the DUT where it needs it first
 * (cf_reset, cf_start_up).
 *
 * No globals: cf_t is caller-owned (large: keep it in static storage). Time comes from the link. */
#ifndef CONFORMANCE_CF_H
#define CONFORMANCE_CF_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_wire.h"
#include "gsd/gsd.h"

#define CF_FRAME_MAX FDL_FRAME_MAX /* 255 */
#define CF_MAX_EVIDENCE 16u
#define CF_TEXT_MAX 256u
#define CF_MAX_CASES 160u
#define CF_MAX_MODULES 32u /* modules in one configuration */
/* How long the run asks for the slave before the first case (it may be searching the rate). */
#define CF_FIND_SLAVE_MS 10000u
/* How long it waits for each of those answers on a wall-clock medium (at most the slot time). */
#define CF_FIND_SLAVE_WAIT_US 10000u
/* cf_settle listens until this many slot times pass in silence, at most the second many. */
#define CF_SETTLE_QUIET_SLOTS 2u
#define CF_SETTLE_MAX_SLOTS 20u
/* TSDR of a reply the medium cannot time (a PTY, an LCM segment, a tty without --timing). */
#define CF_TSDR_UNKNOWN (-1)

typedef enum cf_verdict {
    CF_PASS = 0,
    CF_FAIL,
    CF_NA, /* NOT APPLICABLE: the GSD does not claim the feature, or the medium cannot show it */
} cf_verdict_t;

/* One telegram on the line, as evidence. */
typedef struct cf_frame {
    uint8_t octets[CF_FRAME_MAX];
    uint16_t len;       /* 0 with from_tester false: no answer came (a silent slot) */
    bool from_tester;
    uint64_t t_ns;      /* its first start bit, on the medium's timeline */
    int32_t tsdr_bits;  /* an answer's station delay, or CF_TSDR_UNKNOWN */
    uint32_t baud;
} cf_frame_t;

/* What one request brought back. */
typedef struct cf_reply {
    uint8_t octets[CF_FRAME_MAX];
    uint16_t len;      /* 0: silence until the slot time ran out */
    bool garbled;      /* characters came that make no valid telegram (octets holds them) */
    uint64_t t_ns;     /* its first start bit */
    int32_t tsdr_bits; /* CF_TSDR_UNKNOWN where the medium cannot time it */
    uint64_t tx_t_ns;  /* when the request's first start bit went out */
} cf_reply_t;

/* The device under test as the suite reaches it. A link carries whole telegrams: exchange sends
 * one (after the idle time the line needs, TSYN at least) and waits for the first telegram back.
 * Implementations: cf_rig.h (the card in process on the in-memory bus, a tty/PTY, an LCM segment). */
typedef struct cf_link_ops {
    /* Sends octets (any octets: a test may send broken telegrams) and waits up to wait_us after
     * the last of them for an answer; 0, or -1 when the medium failed (the run ends). */
    int (*exchange)(void *ctx, const uint8_t *octets, size_t len, uint32_t wait_us,
                    cf_reply_t *out);
    /* The line stays silent for us (a watchdog test waits). 0 or -1 as exchange. */
    int (*pause)(void *ctx, uint32_t us);
    /* The tester's rate (the baud search tests); -1 where the medium has no rate (a PTY). */
    int (*set_baud)(void *ctx, uint32_t baud);
    uint64_t (*now_ns)(void *ctx);
    /* Optional (NULL): switch the DUT off and on (in process only). */
    int (*power_cycle)(void *ctx);
    /* Listens without answering until no character has come for quiet_us, at most about
     * max_us: answers still under way to earlier sends (a slave that answered late, or that
     * found a backlog of requests in its receiver when it started) go unheard. 0 or -1. */
    int (*settle)(void *ctx, uint32_t quiet_us, uint32_t max_us);
} cf_link_ops_t;

typedef struct cf_link {
    const cf_link_ops_t *ops;
    void *ctx;
    const char *name;   /* "the card in process", "/dev/pts/3", ... */
    uint32_t baud;      /* the rate the run starts at (0 on a medium without one) */
    bool timing;        /* answers are timed to the bit (tsdr_bits meaningful) */
    bool has_baud;      /* set_baud changes the rate on the wire */
    uint32_t slot_us;   /* how long to wait for an answer (the slot time) */
    uint32_t idle_us;   /* idle the tester keeps before each request (at least TSYN) */
    uint8_t retries;    /* cf_request: repetitions of an unanswered request (a late answer);
                         * where non-zero, the answers to repeated sends are settled */
} cf_link_t;

typedef struct cf cf_t;

typedef struct cf_case {
    const char *id;     /* "dp.set_prm.lock": group prefix, then what it checks */
    const char *group;  /* one of cf_group_names() */
    const char *clause; /* "IEC 61158-6-3 8.3.4", "EN 50170 vol. 2 8.3.2.4" ... */
    const char *title;  /* one line: what a conforming slave does */
    void (*run)(cf_t *cf);
} cf_case_t;

typedef struct cf_result {
    const cf_case_t *c;
    cf_verdict_t verdict;
    char reason[CF_TEXT_MAX]; /* FAIL: what was wrong; NA: why not applicable; PASS: "" */
    char info[CF_TEXT_MAX];   /* anything worth telling beside the verdict (the frame form) */
    cf_frame_t ev[CF_MAX_EVIDENCE]; /* the last telegrams of the case, oldest first */
    uint8_t n_ev;
    uint32_t telegrams;       /* all telegrams of the case (evidence keeps the last ones) */
    uint64_t t_start_ns, t_end_ns;
} cf_result_t;

/* What the run is told beyond the GSD. */
typedef struct cf_options {
    uint8_t address;        /* the DUT */
    uint8_t master;         /* the tester's class-1 address (default 1) */
    uint8_t master_2;       /* a second class-1 master (default 3) */
    uint8_t class2;         /* the class-2 master (default 2) */
    int module;             /* the GSD module configured in start-ups; -1: the first */
    /* A modular station's configuration: these modules in this order (n_modules > 0 overrides
     * module). */
    int modules[CF_MAX_MODULES];
    size_t n_modules;
    const char *only;       /* run the cases whose id starts with this (NULL: all) */
    uint32_t watchdog_ms;   /* the watchdog start-ups set (default 200) */
} cf_options_t;

/* Optional callbacks while the suite runs (a terminal's progress). */
typedef struct cf_hooks {
    void (*case_done)(void *ctx, const cf_result_t *r, size_t index, size_t total);
    void *ctx;
} cf_hooks_t;

struct cf {
    cf_link_t link;
    const gsd_t *gsd;
    cf_options_t opt;
    cf_hooks_t hooks;
    /* The DUT as the GSD describes it (filled by cf_init). */
    uint16_t ident;
    bool dpv1;                     /* DPV1_Slave = 1 */
    uint8_t prm[244];              /* a Set_Prm DU a master would send (cf_default_prm) */
    uint8_t prm_len;
    uint8_t cfg[244];              /* the configured module's identifiers */
    uint8_t cfg_len;
    uint16_t in_len, out_len;      /* its I/O lengths */
    /* FCB state per master address as the tester uses them (FDL 'frame count bit'). */
    bool fcb_started[128];
    bool fcb[128];
    /* The case running and the results so far. */
    cf_result_t *cur;
    bool found;                    /* the slave answered before the cases began */
    uint64_t found_after_ns;       /* how long that took (a baud search) */
    bool link_failed;
    char link_error[CF_TEXT_MAX];
    cf_result_t results[CF_MAX_CASES];
    size_t n_results;
};

/* ---- the run ------------------------------------------------------------------------------ */

/* Prepares a run: the GSD's ident, DP-V1 flag, default Set_Prm and configuration. Returns 0, or
 * -1 with the reason in err (a module index the GSD does not have, parameters that do not fit). */
int cf_init(cf_t *cf, const cf_link_t *link, const gsd_t *gsd, const cf_options_t *opt,
            char *err, size_t errlen);
/* Runs every case of cases (n of them) whose id matches opt.only; results in cf->results. */
void cf_run(cf_t *cf, const cf_case_t *cases, size_t n);
/* All cases of the suite in report order (the groups' tables joined) into out; returns how
 * many (at most cap). */
size_t cf_all_cases(cf_case_t *out, size_t cap);
/* The groups in report order: "GSD", "FDL", "DP state machine", "Timing", "DP-V1". */
const char *const *cf_group_names(size_t *n);
/* Counts by verdict. */
void cf_count(const cf_t *cf, size_t *pass, size_t *fail, size_t *na);
const char *cf_verdict_name(cf_verdict_t v); /* "PASS", "FAIL", "NOT APPLICABLE" */

/* ---- inside a case: verdicts -------------------------------------------------------------- */

/* A case that returns without cf_fail/cf_na passes. The first cf_fail or cf_na decides; later
 * calls add nothing. Each returns false so a case can write `return (void)cf_fail(...)` or
 * `if (!cf_check(...)) return;`. */
bool cf_fail(cf_t *cf, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
bool cf_na(cf_t *cf, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* cf_fail(fmt...) unless ok; returns ok. */
bool cf_check(cf_t *cf, bool ok, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* Information beside the verdict (appended, "; " between). */
void cf_info(cf_t *cf, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* True once the case has failed or been found not applicable (stop early). */
bool cf_decided(const cf_t *cf);

/* ---- inside a case: the wire -------------------------------------------------------------- */

/* Sends raw octets and waits a slot time for the answer; both become evidence. False when the
 * medium failed (the case is then FAIL "link: ..." and the run stops). */
bool cf_exchange(cf_t *cf, const uint8_t *octets, size_t len, cf_reply_t *out);
/* The same with another wait (an SDN or broadcast: how long to listen for a wrong answer). */
bool cf_exchange_wait(cf_t *cf, const uint8_t *octets, size_t len, uint32_t wait_us,
                      cf_reply_t *out);
bool cf_pause_ms(cf_t *cf, uint32_t ms);
/* Where the link can (cf_link_ops_t.settle): lets answers still under way to earlier sends come
 * and go unheard, until two slot times pass in silence. False when the medium failed. */
bool cf_settle(cf_t *cf);

/* A request from master sa to the DUT: fc's function code (FDL_REQ_*) with FCV/FCB set by the
 * FDL rules for that master (first request FCV=0 FCB=1, then FCV=1 and FCB toggling; only for
 * SRD/SDA), DSAP/SSAP when dsap >= 0 (ssap then too), du of du_len octets. The DA is the DUT. */
bool cf_request(cf_t *cf, uint8_t sa, uint8_t fc_code, int dsap, int ssap, const uint8_t *du,
                size_t du_len, cf_reply_t *out);
/* A DP service of the tester's class-1 master: SRD high priority to dsap from SSAP 62. */
bool cf_dp(cf_t *cf, uint8_t dsap, const uint8_t *du, size_t du_len, cf_reply_t *out);
/* The same from another master address (and SSAP). */
bool cf_dp_from(cf_t *cf, uint8_t sa, uint8_t ssap, uint8_t dsap, const uint8_t *du,
                size_t du_len, cf_reply_t *out);
/* Data_Exchange (no SAPs) with these outputs. */
bool cf_data_exchange(cf_t *cf, const uint8_t *out_data, size_t len, cf_reply_t *out);
/* Forget the FCB state of master sa: its next request starts again with FCV=0. */
void cf_fcb_restart(cf_t *cf, uint8_t sa);

/* ---- reading answers ---------------------------------------------------------------------- */

/* The answer's parts: false when it is no valid data telegram (SC, garbled, none). */
typedef struct cf_answer {
    uint8_t sd, da, sa, fc;
    bool saps;
    uint8_t dsap, ssap;
    const uint8_t *du; /* after the SAP octets */
    uint8_t du_len;
} cf_answer_t;
bool cf_answer(const cf_reply_t *r, cf_answer_t *a);
/* The answer is SC (E5). */
bool cf_is_sc(const cf_reply_t *r);
/* A positive acknowledgement without data: SC, or SD1 with OK, DL, DH or NR (IEC 61158-4-3
 * lets a responder answer an SRD that returns nothing either way). */
bool cf_is_ack(const cf_reply_t *r);
/* The response code of the answer (FDL_RSP_*), -1 for SC, silence or garbage. */
int cf_rsp_code(const cf_reply_t *r);
/* The name of a response code (FDL_RSP_*): "RS", "DL" ... */
const char *cf_rsp_name(int code);
/* A text of a reply for a reason: "silence", "SC", "RS (FC 0x03)", "DL 6 octets" ... */
const char *cf_reply_text(const cf_reply_t *r, char *buf, size_t n);

/* ---- start-up helpers --------------------------------------------------------------------- */

/* Slave_Diag by the tester's master: the diagnosis octets (at least 6) or false (the case has
 * then failed, with the reason). */
bool cf_diag(cf_t *cf, uint8_t *diag, size_t *len);
/* Set_Prm DU as a master builds it from the GSD: station status with lock (and WD_On with
 * watchdog_ms when > 0), watchdog factors, min TSDR 11, ident, group 0, user parameters (DP-V1
 * status octets with DPV1_Enable when the GSD claims DPV1_Slave). Returns its length. */
size_t cf_default_prm(const cf_t *cf, uint32_t watchdog_ms, uint8_t *out, size_t cap);
/* Leaves the DUT unlocked in Wait_Prm: Set_Prm with Unlock_Req (lock released, as a master
 * that ends does), from every master address a case may have used. */
bool cf_reset(cf_t *cf);
/* Brings the DUT to Data_Exch from the tester: reset, Slave_Diag, Set_Prm (cf->prm), Chk_Cfg
 * (cf->cfg), Slave_Diag until ready, one Data_Exchange. False (failed, with reason) if not. */
bool cf_start_up(cf_t *cf);

#endif
