/* The LCM event-log backend of capture.c (internal to the dfp_capture library). A log written by
 * lcm-logger holds events of every channel; the reader hands over the dfp_lcm telegram messages
 * (sim_host/lcm_bridge/) of the chosen channel (cap_reader_open_channel) and skips other events. */
#ifndef CAPTURE_CAP_LCM_H
#define CAPTURE_CAP_LCM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/capture.h"

/* True when head (the first n octets of a file) starts like an LCM event log (sync word
 * 0xEDA1DA01, big-endian). */
bool cap_lcm_sniff(const uint8_t *head, size_t n);
/* r->path is set and r->format is CAP_FORMAT_LCM; channel as for cap_reader_open_channel.
 * Returns 0, or -1 with the reason in err. */
int cap_lcm_open(cap_reader_t *r, const char *channel, char *err, size_t errlen);
/* Same contract as cap_reader_next: 1 record, 0 end, -1 error in r->error (with the event
 * number / byte offset). Events that are not telegrams are skipped. */
int cap_lcm_next(cap_reader_t *r, cap_record_t *rec);
void cap_lcm_close(cap_reader_t *r);

#endif
