/* Classic pcap records read in chunks (internal to the dfp_capture library). libpcap opens the
 * file and checks its header and link type (capture.c); the records are then read here straight
 * from the file, a chunk at a time, because libpcap's two fread() calls per record were a tenth
 * of a replay's time. pcapng and the pcap variants other than the four standard magics stay
 * with libpcap. */
#ifndef CAPTURE_CAP_PCAP_H
#define CAPTURE_CAP_PCAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/capture.h"

#define PCAP_FILE_HEADER_LEN 24u   /* magic, version, zone, sigfigs, snaplen, link type */
#define PCAP_RECORD_HEADER_LEN 16u /* seconds, fraction, captured and wire length */

/* After libpcap opened r->path as classic pcap: true when its magic is one of the four standard
 * ones, and the records are to be read with cap_pcap_next. */
bool cap_pcap_chunked_start(cap_reader_t *r);
/* Same contract as cap_reader_next, for a reader cap_pcap_chunked_start accepted. */
int cap_pcap_next(cap_reader_t *r, cap_record_t *rec);

/* capture.c's part of every pcap record, whoever read it: the octets, the telegram check and
 * the notes on cut or damaged record headers. */
void cap_pcap_fill(cap_reader_t *r, cap_record_t *rec, uint64_t t_ns, const uint8_t *data,
                   uint32_t caplen, uint32_t wire_len);

#endif
