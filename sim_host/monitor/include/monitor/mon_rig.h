/* A monitor on a running rig, for the control API (the monitor on a line of its own, for
 * `dfp-sim monitor`, is mon_live.h): it hears every telegram of the rig's line
 * (a rig tap), logs its events into the rig_ctl event ring (source "station N", kind "bus":
 * GET /api/v1/log and the event stream) and publishes its JSON document (MON_JSON, served as
 * GET /api/v1/bus) every MON_RIG_PUBLISH_NS through a rig_doc_t that HTTP threads copy.
 *
 * Everything runs in the rig's loop thread: the tap, mon_rig_service. Nothing here waits on a
 * client. Large (the monitor, 285 KB, and RIG_DOC_BUFS documents of RIG_DOC_CAP: 4.5 MB):
 * static or heap storage, never on a thread's stack. */
#ifndef MONITOR_MON_RIG_H
#define MONITOR_MON_RIG_H

#include <stdbool.h>
#include <stdint.h>

#include "monitor/monitor.h"
#include "rig/rig.h"
#include "rig/rig_ctl.h"
#include "rig/rig_doc.h"

#define MON_RIG_PUBLISH_NS 500000000u /* the panel's bus page refreshes about once a second */
#define MON_RIG_LAST_EVENTS 100u      /* the newest events the document lists */
/* The monitor's events the log takes in one second: a station sending an illegal telegram in
 * every cycle must not push every other event out of the API's ring of RIG_CTL_EVENTS, nor
 * keep the loop publishing. The rest of the second is counted in one line. */
#define MON_RIG_EVENTS_PER_S 20u

typedef struct mon_rig {
    mon_t mon;
    rig_doc_t doc;
    rig_ctl_t *ctl;
    char source[96];      /* "monitor.source" of the document: what the monitor listens to */
    uint64_t t0_ns;       /* the rig's clock when the monitor started: the document counts
                             its times from it */
    uint64_t last_end_ns; /* the end of the newest telegram fed: mon_idle never goes back */
    uint64_t idle_ns;     /* the last mon_idle: no telegram is fed as older */
    uint64_t last_publish_ns;
    bool published;
    uint64_t window_ns;   /* start of the second the logged events are counted in */
    uint32_t window_n;
    uint64_t not_logged;  /* events of that second beyond MON_RIG_EVENTS_PER_S */
} mon_rig_t;

/* Starts the monitor (cfg's on_event and ctx are replaced: the events go to ctl) and gives ctl
 * its document (ctl->bus). Call after rig_ctl_init and before the HTTP server starts. Times
 * are the rig's clock (rig_elapsed_ns), the one its taps give. */
void mon_rig_init(mon_rig_t *l, rig_ctl_t *ctl, const mon_cfg_t *cfg, const char *source,
                  uint64_t now_ns);
/* The tap that feeds it every telegram of the rig's line (rig_add_tap). */
rig_tap_t mon_rig_tap(mon_rig_t *l);
/* From the loop, often: time passes for the monitor (answers that did not come), and the
 * document is published when the last one is MON_RIG_PUBLISH_NS old. now_ns: the rig's
 * clock. */
void mon_rig_service(mon_rig_t *l, uint64_t now_ns);
/* Publishes the document now (skipped while every buffer is being read). */
void mon_rig_publish(mon_rig_t *l, uint64_t now_ns);

#endif
