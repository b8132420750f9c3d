/* The master's parameter services for rig_ctl.c (private to the rig library): the cyclic
 * MOVILINK channel, data set 47 over class 1, and data set 47 over a class-2 connection. One
 * runs at a time, started by rig_ctl_param_start and moved along on every service turn. */
#ifndef RIG_CTL_PARAM_H
#define RIG_CTL_PARAM_H

#include <stdbool.h>
#include <stdio.h>

#include "rig/rig_ctl.h"

static inline void rig_cmd_fail(rig_cmd_t *cmd, int status, const char *text)
{
    cmd->status = status;
    (void)snprintf(cmd->error, sizeof cmd->error, "%s", text);
}

/* The master's slave entry for a bus address, -1 if it has none. */
int rig_ctl_slave_index(const dp_master_t *m, uint8_t address);
/* The slave's configuration carries the 8-octet parameter channel (F3/B7) before the PD. */
bool rig_ctl_has_param_channel(const dp_master_slave_t *sl);

/* Starts cmd (RIG_CMD_MASTER_PARAM); false when it finished at once (cmd has the error). */
bool rig_ctl_param_start(rig_ctl_t *c, rig_cmd_t *cmd);
/* The running service: true when it finished (cmd has the result). */
bool rig_ctl_param_advance(rig_ctl_t *c, rig_cmd_t *cmd);
/* The service ran out of time: leaves nothing open on the bus. */
void rig_ctl_param_give_up(rig_ctl_t *c);

#endif
