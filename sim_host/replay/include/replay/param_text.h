/* MOVILINK parameter services in captured telegrams, named for people: the cyclic parameter
 * channel of Data_Exchange and data set 47 over DP-V1 ("write P100 setpoint source (8461) = 3
 * (FIELDBUS)"), with the names of the emulated MOVIDRIVE (movidrive/movidrive_names.h). Pure
 * functions; the caller keeps the little context a data set 47 answer needs (which parameter was
 * asked). */
#ifndef REPLAY_PARAM_TEXT_H
#define REPLAY_PARAM_TEXT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "replay/decode.h"

/* The last data set 47 request seen: its answer carries values, not parameter numbers. */
typedef struct replay_param_ctx {
    bool ds47_pending;
    uint8_t ds47_id;      /* DS47_ID_* */
    uint8_t ds47_service; /* ML_SVC_* of its first parameter */
    uint16_t ds47_index;  /* its first parameter */
} replay_param_ctx_t;

/* One line about the parameter service a telegram carries, or "" (returns 0) when it carries
 * none. ctx may be NULL (a data set 47 answer is then not named); lay as for replay_describe. */
size_t replay_param_text(const uint8_t *f, size_t len, const replay_dx_layout_t *lay,
                         replay_param_ctx_t *ctx, char *out, size_t max);
/* The cyclic parameter channel alone: the 8 octets m that lead a Data_Exchange DU when the
 * configuration has one (a request when reply is false). "" (returns 0) when it carries no
 * service. The monitor names a slave's last outputs and inputs with it. */
size_t replay_channel_text(const uint8_t *m, bool reply, char *out, size_t max);

#endif
