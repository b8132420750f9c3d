/* Decoding a telegram_t from octets that may be anything (a log file, the network).
 *
 * lcm-gen's decoder trusts the message's own length field: a negative one makes it copy
 * gigabytes. This checks the fingerprint, the fixed part and that the length field is exactly
 * what the buffer holds before handing over to the generated decoder. */
#ifndef DFP_LCM_TYPES_TELEGRAM_DECODE_H
#define DFP_LCM_TYPES_TELEGRAM_DECODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dfp_lcm/dfp_lcm_telegram_t.h"

/* Encoded size of a telegram_t without its data octets: 8 fingerprint octets and the fixed
 * fields up to and including length. */
#define DFP_LCM_TELEGRAM_FIXED 39u

/* True when buf starts with telegram_t's fingerprint (the message is meant to be one). */
bool dfp_lcm_is_telegram(const void *buf, size_t len);
/* Returns 0 with *out decoded (free with dfp_lcm_telegram_t_decode_cleanup), or -1 with the
 * reason in why ("length field -3", "7 octets after the data"...). */
int dfp_lcm_telegram_decode_checked(const void *buf, size_t len, dfp_lcm_telegram_t *out,
                                    char *why, size_t why_max);

#endif
