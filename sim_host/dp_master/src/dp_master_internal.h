/* What dp_master.c shares with its other parts (dp_master_ring.c); not for users. */
#ifndef DP_MASTER_INTERNAL_H
#define DP_MASTER_INTERNAL_H

#include "dp_master/dp_master.h"

void dpm_set_phase(dp_master_t *m, unsigned idx, dp_master_phase_t next, hal_time_us_t t);
/* A pending Global_Control as a broadcast SDN. */
void dpm_send_global_control(dp_master_t *m, hal_time_us_t now);
/* One telegram of an attached class-2 connection that has something to send. */
bool dpm_send_c2(dp_master_t *m, hal_time_us_t now);
/* The slave's next telegram: a class-1 acyclic one (c1) or its phase's cyclic one. */
void dpm_send_to_slave(dp_master_t *m, unsigned idx, bool c1, hal_time_us_t now);
/* Nothing to send now: the earliest instant something will be (only when no slave is due). */
hal_time_us_t dpm_idle_until(dp_master_t *m, hal_time_us_t now);

/* dp_master_ring.c: the station's set-up from cfg.bus, and dp_master_poll with the token. */
void dpm_ring_init(dp_master_t *m, hal_time_us_t now);
hal_time_us_t dpm_ring_poll(dp_master_t *m, hal_time_us_t now);

#endif
