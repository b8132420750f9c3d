/* dfp-sim convert: one capture file into another format or link type, record by record (so a
 * capture of any length converts in constant memory). The usual use: a PROFIBUS_DL (257) pcap,
 * which no Wireshark release maps, into USER0 (147) for the Lua dissector in tools/wireshark/,
 * or a text dump into pcapng and back. Damaged records are copied as they are and reported. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"

/* Enough to locate the trouble without flooding a terminal for a badly damaged file. */
#define CONVERT_MAX_REPORTED 10u

int cmd_convert(int argc, char **argv)
{
    const char *in = NULL;
    const char *out = NULL;
    cap_format_t in_format = CAP_FORMAT_AUTO;
    cap_writer_options_t w = {.format = CAP_FORMAT_AUTO, .linktype = 0};
    bool quiet = false;
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i];
        if (strcmp(o, "--format") == 0 || strcmp(o, "--in-format") == 0) {
            const char *v = cli_value(argc, argv, &i);
            if (v == NULL) return EXIT_USAGE;
            cap_format_t f;
            bool out_side = strcmp(o, "--format") == 0;
            if (!cap_format_parse(v, &f) || f == CAP_FORMAT_AUTO ||
                (out_side && f == CAP_FORMAT_LCM)) {
                cli_error("%s: '%s' is not one of %s", o, v,
                          out_side ? "pcap, pcapng, text" : "pcap, pcapng, text, lcm");
                return EXIT_USAGE;
            }
            *(out_side ? &w.format : &in_format) = f;
        } else if (strcmp(o, "--linktype") == 0) {
            const char *v = cli_value(argc, argv, &i);
            if (v == NULL) return EXIT_USAGE;
            if (strcmp(v, "profibus") == 0 || strcmp(v, "257") == 0) {
                w.linktype = PCAP_LINKTYPE_PROFIBUS_DL;
            } else if (strcmp(v, "user0") == 0 || strcmp(v, "147") == 0) {
                w.linktype = PCAP_LINKTYPE_USER0;
            } else {
                cli_error("--linktype: '%s' is not profibus (257) or user0 (147)", v);
                return EXIT_USAGE;
            }
        } else if (strcmp(o, "--ns") == 0) {
            w.nanosecond = true;
        } else if (strcmp(o, "--quiet") == 0) {
            quiet = true;
        } else if (o[0] == '-' && o[1] != '\0') {
            cli_error("convert: unknown option '%s' (see dfp-sim --help)", o);
            return EXIT_USAGE;
        } else if (in == NULL) {
            in = o;
        } else if (out == NULL) {
            out = o;
        } else {
            cli_error("convert takes two files, IN and OUT; '%s' is a third", o);
            return EXIT_USAGE;
        }
    }
    if (in == NULL || out == NULL) {
        cli_error("convert needs an input and an output file: dfp-sim convert IN OUT");
        return EXIT_USAGE;
    }
    if (strcmp(in, out) == 0) {
        cli_error("convert: IN and OUT are the same file (%s)", in);
        return EXIT_USAGE;
    }

    static cap_reader_t reader;
    static cap_record_t rec;
    char err[1100];
    if (cap_reader_open(&reader, in, in_format, err, sizeof err) != 0) {
        cli_error("%s", err);
        return EXIT_USAGE;
    }
    /* The first record is read before the output is opened: its baud rate, when the input has
     * one, goes into the pcapng interface description. */
    int rc = cap_reader_next(&reader, &rec);
    if (rc == 1) {
        w.baud = rec.baud;
    }
    if (w.linktype == 0 && reader.linktype != 0) {
        w.linktype = reader.linktype;
    }
    static cap_writer_t writer;
    if (cap_writer_open(&writer, out, &w, 0, err, sizeof err) != 0) {
        cli_error("%s", err);
        cap_reader_close(&reader);
        return 1;
    }
    uint64_t damaged = 0;
    bool write_failed = false;
    for (; rc == 1; rc = cap_reader_next(&reader, &rec)) {
        if (rec.problem[0] != '\0') {
            damaged++;
            if (damaged <= CONVERT_MAX_REPORTED && !quiet) {
                fprintf(stderr, "dfp-sim: %s: record %" PRIu64 " (%s %" PRIu64 "): %s\n", in,
                        rec.index, reader.format == CAP_FORMAT_TEXT ? "line" : "byte",
                        rec.position, rec.problem);
            }
            if (rec.len == 0) {
                continue; /* a text line that is no telegram: nothing to write */
            }
        }
        if (cap_writer_frame(&writer, rec.t_ns, rec.data, rec.len, rec.dir) != 0) {
            write_failed = true;
            break;
        }
    }
    cap_format_t in_fmt = reader.format;
    if (rc < 0) {
        cli_error("%s", reader.error);
    }
    cap_reader_close(&reader);
    cap_writer_options_t written = writer.opt;
    uint64_t records = writer.records;
    if (cap_writer_close(&writer) != 0 || write_failed) {
        cli_error("could not write the whole capture to %s", out);
        return 1;
    }
    if (records == 0 && damaged > 0) {
        cli_error("%s: none of its %" PRIu64 " records is a telegram", in, damaged);
        return 1;
    }
    if (!quiet) {
        printf("%s (%s) -> %s (%s", in, cap_format_name(in_fmt), out,
               cap_format_name(written.format));
        if (written.format != CAP_FORMAT_TEXT) {
            printf(", link type %u, %s", written.linktype,
                   written.nanosecond ? "ns" : "µs");
        }
        printf("): %" PRIu64 " records", records);
        if (damaged > 0) {
            printf(", %" PRIu64 " damaged (reported above%s)", damaged,
                   damaged > CONVERT_MAX_REPORTED ? ", the first 10" : "");
        }
        printf("\n");
    }
    return rc < 0 ? 1 : 0;
}
