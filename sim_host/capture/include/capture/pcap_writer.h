/* pcap files of bus telegrams. LINKTYPE_PROFIBUS_DL (257) stores each telegram from its start
 * delimiter to its end delimiter with no pseudo-header (protocol.md §A6); an SC is stored as
 * its single octet and a token (SD4) as its three octets, as they are on the wire. */
#ifndef CAPTURE_PCAP_WRITER_H
#define CAPTURE_PCAP_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define PCAP_LINKTYPE_PROFIBUS_DL 257u
#define PCAP_LINKTYPE_USER0 147u

typedef struct pcap_writer {
    FILE *f;
    bool nanosecond;
    uint64_t base_ns; /* added to every record's time (e.g. wall clock at start) */
    uint64_t records;
    char path[512];
} pcap_writer_t;

/* Returns 0, or -1 with a one-line reason in err. */
int pcap_writer_open(pcap_writer_t *w, const char *path, uint32_t linktype, bool nanosecond,
                     uint64_t base_ns, char *err, size_t errlen);
int pcap_writer_frame(pcap_writer_t *w, uint64_t t_ns, const uint8_t *frame, size_t len);
/* Flushes and closes; returns -1 if anything could not be written. */
int pcap_writer_close(pcap_writer_t *w);

#endif
