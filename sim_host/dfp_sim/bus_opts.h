/* The bus parameters of a master's FDL active station (fdl_active.h) as options, shared by
 * every command that runs a master: --bus-profile dp|usb and one option per parameter. They
 * must match those of every other master on the segment (a PLC's "bus parameters"). */
#ifndef DFP_SIM_BUS_OPTS_H
#define DFP_SIM_BUS_OPTS_H

#include <stdbool.h>
#include <stdint.h>

#include "cli_table.h"
#include "fdl_active/fdl_active.h"

typedef struct bus_opts {
    int profile; /* fdl_bus_profile_t, or -1: by the medium */
    uint32_t tsl, min_tsdr, max_tsdr, tset, tqui, ttr, gap, hsa, retry;
    bool tsl_seen, min_tsdr_seen, max_tsdr_seen, tset_seen, tqui_seen, ttr_seen, gap_seen,
        hsa_seen, retry_seen;
} bus_opts_t;

extern const cli_opt_t bus_options[10];

/* Before parsing: no profile chosen, nothing given. */
void bus_opts_defaults(bus_opts_t *o);
/* The parameters at baud: the profile (dp on the in-memory bus, usb on a tty, PTY or LCM
 * segment, whose timing is the host's), then each option given. False after reporting a rule
 * they break (fdl_bus_params_check). */
bool bus_opts_apply(const bus_opts_t *o, const char *cmd, uint32_t baud, bool wall_clock,
                    fdl_bus_params_t *out);
/* A master's own address (named by opt) above HSA is never asked by anyone's GAP maintenance,
 * so it could join no ring it did not start itself. False after reporting. */
bool bus_opts_own_ok(const fdl_bus_params_t *p, const char *cmd, const char *opt, uint32_t own);
/* Any bus option given (for commands where they need a master). */
bool bus_opts_given(const bus_opts_t *o);

#endif
