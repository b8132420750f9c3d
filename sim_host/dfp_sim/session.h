/* One wall-clock run of slave or master: the rig on a tty or an LCM segment, with the log and
 * control API (instrument), the capture (report) and the LCM telemetry (--lcm URL) attached.
 * The struct is large (a rig): keep it in static storage. */
#ifndef DFP_SIM_SESSION_H
#define DFP_SIM_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "instrument.h"
#include "lcm_cli.h"
#include "medium.h"
#include "report.h"
#include "rig/rig.h"

typedef struct session {
    rig_t rig;
    instrument_t in;
    report_t rep;
    lcm_cli_t telemetry; /* --lcm URL */
} session_t;

/* Builds the rig on the port or the segment with the log, capture and telemetry taps, and
 * catches SIGINT/SIGTERM. Returns false after reporting the reason (nothing left open). With
 * m->use_fd the session owns m->fd from the call on, and closes it on failure too. */
bool session_open(session_t *s, const medium_opts_t *m, int16_t station_address, uint32_t baud,
                  const capture_opts_t *capture, const instrument_opts_t *io, bool echo);
/* --lcm URL: the telemetry of card, with the medium's own time origin. Returns 0 or -1. */
int session_telemetry(session_t *s, const char *url, const dfp21b_t *card, uint8_t address);
/* The medium as the start line names it (buf: 300 octets are enough). */
const char *session_medium_name(const session_t *s, const medium_opts_t *m, char *buf,
                                size_t n);
/* Stops the control API and closes the medium; the capture stays open. */
void session_close(session_t *s);
/* session_close, the telemetry and the capture: rc, or 1 when the capture could not be
 * finished. */
int session_end(session_t *s, int rc);

#endif
