/* The monitor on a ring rig (tests/ring/ring_rig.h): every telegram on the in-memory bus goes to
 * a mon_t as a receive-only station sees it, and the events it reports are kept in order. The
 * tap also keeps its own tally (requests per address, repeats as identical octets) so the
 * monitor's counts are checked against something it did not compute. */
#ifndef TESTS_MONITOR_RING_MON_H
#define TESTS_MONITOR_RING_MON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "monitor/monitor.h"
#include "ring_rig.h"

#define MON_RIG_EVENTS 8192u

typedef struct ring_mon_ev {
    mon_event_type_t type;
    uint8_t station;
    uint8_t other;
    uint32_t value;
    uint64_t t_ns;
} ring_mon_ev_t;

typedef struct ring_mon {
    ring_rig_t rr;
    mon_t mon;
    ring_mon_ev_t ev[MON_RIG_EVENTS];
    size_t num_ev;
    /* the tap's own tally */
    uint64_t requests_to[MON_STATIONS];
    uint64_t same_octets_to[MON_STATIONS]; /* FCV set, identical to the request before it */
    uint8_t last_req[MON_STATIONS][24];
    uint8_t last_req_len[MON_STATIONS];
    uint32_t req[MON_STATIONS][MON_STATIONS];     /* requests [from][to] */
    uint32_t set_prm[MON_STATIONS][MON_STATIONS]; /* Set_Prm requests [from][to] */
} ring_mon_t;

/* ring_rig_init with cards that each drive an emulated MOVIDRIVE, then the monitor (timing true,
 * the DP profile's slot time) on its tap. */
void ring_mon_init(ring_mon_t *r, uint32_t baud, const uint8_t *cards, size_t num_cards);
/* Runs ms milliseconds in 1 ms steps, telling the monitor the time after each (mon_idle). */
void ring_mon_run_ms(ring_mon_t *r, unsigned ms);
/* Index of the first event of type for station at or after from (r->num_ev: none). */
size_t ring_mon_find(const ring_mon_t *r, size_t from, mon_event_type_t type, uint8_t station);
/* Events of type for station at or after from. */
unsigned ring_mon_count(const ring_mon_t *r, size_t from, mon_event_type_t type, uint8_t station);
/* Events of type (any station) at or after from. */
unsigned ring_mon_count_type(const ring_mon_t *r, size_t from, mon_event_type_t type);
/* Addresses the monitor has heard (seen), ascending, into out; their number. */
size_t ring_mon_live(const ring_mon_t *r, uint8_t *out, size_t cap);
/* The events from from on stderr: what a failed check looks at. */
void ring_mon_dump_events(const ring_mon_t *r, size_t from);

#endif
