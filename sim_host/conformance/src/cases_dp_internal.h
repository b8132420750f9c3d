/* Helpers shared by the DP state machine cases (cases_dp_*.c). Each checks what it reads and
 * fails the running case with a reason saying what was expected and what came; they return
 * false then, so a case can stop with `if (!...) return;`. */
#ifndef CONFORMANCE_CASES_DP_INTERNAL_H
#define CONFORMANCE_CASES_DP_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "conformance/cf.h"

#define DPX_DIAG_MAX 244u
#define DPX_HEX_MAX 100u /* a hex text of up to 32 octets, "..." after */

/* The case's name for a clause text shared by several cases. */
#define DPX_STATE_MACHINE "IEC 61158-6-3 / EN 50170 vol. 2 DP slave state machine"

/* "02 05 00 FF 60 03" (up to 32 octets, then "..."). */
const char *dpx_hex(const uint8_t *p, size_t n, char *buf, size_t cap);
/* An answer that acknowledges without data: SC, or SD1 with DL, DH or NR and no data. */
bool dpx_is_ack(const cf_reply_t *r);
/* An answer with data (DL or DH): its DU in a->du. */
bool dpx_is_data(const cf_reply_t *r, cf_answer_t *a);
/* cf_fail unless the answer acknowledges (what: "Set_Prm in Wait_Prm"). */
bool dpx_expect_ack(cf_t *cf, const cf_reply_t *r, const char *what);
/* cf_fail unless the answer is RS. */
bool dpx_expect_rs(cf_t *cf, const cf_reply_t *r, const char *what);
/* The answer as text into the case's information ("what: RS (FC 0x03)"). */
void dpx_note(cf_t *cf, const cf_reply_t *r, const char *what);

/* Slave_Diag from master sa (SSAP 62): at least 6 octets of DL/DH data, else failed. */
bool dpx_diag_from(cf_t *cf, uint8_t sa, uint8_t *d, size_t *len, const char *what);
/* cf_fail unless (d[octet] & mask) == want; name is the bit or field. */
bool dpx_bits(cf_t *cf, const uint8_t *d, size_t len, size_t octet, uint8_t mask, uint8_t want,
              const char *name, const char *what);

/* The bits of Wait_Prm whatever came before: Station_Not_Ready, Prm_Req, the always-one bit,
 * the master-only bits 0, no Freeze/Sync mode, Master_Add 255. */
bool dpx_wait_prm_bits(cf_t *cf, const uint8_t *d, size_t n, const char *what);

/* The tester's Set_Prm / Chk_Cfg, answered with an acknowledgement. */
bool dpx_set_prm(cf_t *cf, const uint8_t *prm, size_t len, const char *what);
bool dpx_chk_cfg(cf_t *cf, const uint8_t *cfg, size_t len, const char *what);
/* Slave_Diag until the slave is ready for data (no Prm_Req, Stat_Diag, Station_Not_Ready,
 * Cfg_Fault, Prm_Fault), up to a second of polls; the last diagnosis in d. */
bool dpx_wait_ready(cf_t *cf, uint8_t *d, size_t *len, const char *what);
/* Data_Exchange of the tester with out (cf->out_len octets, NULL: zeros), answered with the
 * module's cf->in_len input octets (SC when it has none); the inputs into in (may be NULL). */
bool dpx_dx(cf_t *cf, const uint8_t *out, uint8_t *in, const char *what);
/* Data_Exchange of the tester refused with RS (the slave is not in Data_Exch). */
bool dpx_dx_refused(cf_t *cf, const char *what);
/* Global_Control (SDN to DA 127, DSAP 58) from master sa; cf_fail if anything answers. */
bool dpx_gc(cf_t *cf, uint8_t sa, uint8_t command, uint8_t group);
/* cf_start_up with this Set_Prm DU instead of cf->prm (restored afterwards). */
bool dpx_start_up_with(cf_t *cf, const uint8_t *prm, size_t len);
/* A copy of cf->prm with station status bits set and cleared. Returns its length. */
size_t dpx_prm_with(const cf_t *cf, uint8_t set, uint8_t clear, uint8_t *out);
/* The watchdog time a Set_Prm DU asks for, in ms (0 with WD_On off). */
uint32_t dpx_watchdog_ms(const cf_t *cf, const uint8_t *prm, size_t len);

/* Outputs patterned after seed (never all zero). */
void dpx_pattern(uint8_t *out, size_t len, uint8_t seed);
/* Data_Exchange with out up to tries times until the inputs' tail (the last octets the module
 * has both ways, at most two) equals that of want: the attempt (1..) it did, 0 when it never
 * did, -1 when the case failed. */
int dpx_dx_until(cf_t *cf, const uint8_t *out, const uint8_t *want, int tries, const char *what);
/* Whether the DUT's inputs follow its outputs (a loopback, as the card in process without an
 * inverter): two patterns each come back. -1 when the case failed. */
int dpx_echo_probe(cf_t *cf);

/* The cases (cases_dp_state.c, cases_dp_prm.c, cases_dp_cfg.c, cases_dp_gc.c). */
void dpc_diag_wait_prm(cf_t *cf);
void dpc_wait_prm_services(cf_t *cf);
void dpc_wait_cfg_data_exchange(cf_t *cf);
void dpc_wait_cfg_services(cf_t *cf);
void dpc_data_exch_services(cf_t *cf);
void dpc_diag_data_exch(cf_t *cf);
void dpc_set_prm_lock(cf_t *cf);
void dpc_set_prm_unlock(cf_t *cf);
void dpc_set_prm_min_tsdr_only(cf_t *cf);
void dpc_set_prm_repeated(cf_t *cf);
void dpc_set_prm_wrong_ident(cf_t *cf);
void dpc_set_prm_user_prm(cf_t *cf);
void dpc_set_prm_watchdog_off(cf_t *cf);
void dpc_watchdog_expiry(cf_t *cf);
void dpc_chk_cfg_right(cf_t *cf);
void dpc_chk_cfg_wrong(cf_t *cf);
void dpc_get_cfg(cf_t *cf);
void dpc_global_control_clear(cf_t *cf);
void dpc_global_control_sync(cf_t *cf);
void dpc_global_control_freeze(cf_t *cf);
void dpc_global_control_groups(cf_t *cf);
void dpc_class2_read(cf_t *cf);
void dpc_second_master(cf_t *cf);

#endif
