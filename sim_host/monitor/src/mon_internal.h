/* What the monitor's sources share (not part of the library's interface). */
#ifndef MONITOR_MON_INTERNAL_H
#define MONITOR_MON_INTERNAL_H

#include "dp_slave/fdl_frame.h"
#include "monitor/monitor.h"

void mon_emit(mon_t *m, uint64_t t_ns, mon_event_type_t type, mon_level_t level, uint8_t station,
              uint8_t other, uint32_t value, const char *fmt, ...)
    __attribute__((format(printf, 8, 9)));
void mon_span_add(mon_span_t *s, uint64_t ns);
/* ns in bit times at the line's rate (0 when the rate is unknown). */
uint64_t mon_bits(const mon_t *m, uint64_t ns);
void mon_heard(mon_t *m, uint8_t a, mon_role_t role, uint64_t t_ns);

/* mon_dp.c: a request as it goes out (DP services that need no answer: Global_Control), an
 * answer to the pending request (msg NULL: SC), and a slave that stopped answering. */
void mon_dp_request(mon_t *m, const fdl_msg_t *req, uint64_t t_ns);
void mon_dp_answer(mon_t *m, const fdl_msg_t *rsp, uint64_t t_ns);
void mon_dp_gone(mon_t *m, uint8_t a, uint64_t t_ns);

#endif
