/* dfp-sim convert: one capture file into another format or link type, record by record (so a
 * capture of any length converts in constant memory). The usual use: a PROFIBUS_DL (257) pcap,
 * which no Wireshark release maps, into USER0 (147) for the Lua dissector in tools/wireshark/,
 * or a text dump into pcapng and back. Damaged records are copied as they are and reported. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"

/* Enough to locate the trouble without flooding a terminal for a badly damaged file. */
#define CONVERT_MAX_REPORTED 10u

static bool written_text(const cap_writer_t *w)
{
    return w->opt.format == CAP_FORMAT_TEXT;
}

/* A record without a time, as a bare hex line (text_import reads it back untimed). */
static int write_untimed_text(cap_writer_t *w, const cap_record_t *rec)
{
    for (size_t i = 0; i < rec->len; i++) {
        if (fprintf(w->f, i == 0 ? "%02X" : " %02X", rec->data[i]) < 0) {
            return -1;
        }
    }
    if (fputc('\n', w->f) == EOF) {
        return -1;
    }
    w->records++;
    return 0;
}

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
    /* By identity, not by name: "a.pcap" and "./a.pcap" are one file, and opening OUT for
     * writing would truncate the input under the reader. */
    struct stat in_st;
    struct stat out_st;
    if (strcmp(in, out) == 0 || (stat(in, &in_st) == 0 && stat(out, &out_st) == 0 &&
                                 in_st.st_dev == out_st.st_dev && in_st.st_ino == out_st.st_ino)) {
        cli_error("convert: IN and OUT are the same file (%s, %s)", in, out);
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
    uint64_t untimed = 0;
    uint64_t skipped_empty = 0;
    bool write_failed = false;
    bool untimed_refused = false;
    for (; rc == 1; rc = cap_reader_next(&reader, &rec)) {
        if (rec.problem[0] != '\0') {
            damaged++;
            if (damaged <= CONVERT_MAX_REPORTED && !quiet) {
                fprintf(stderr, "dfp-sim: %s: record %" PRIu64 " (%s %" PRIu64 "): %s\n", in,
                        rec.index, cap_position_unit(reader.format), rec.position,
                        rec.problem);
            }
        }
        if (rec.len == 0 && (reader.format == CAP_FORMAT_TEXT || written_text(&writer))) {
            /* A text line that is no telegram, or an empty record text cannot show. */
            skipped_empty++;
            continue;
        }
        if (!rec.has_time) {
            /* A text dump without times: text keeps it untimed (a bare hex line reads back
             * untimed); pcap and pcapng need a time, and an invented one would be taken for
             * the bus's timing by every later reader (replay infers the rate from it). */
            untimed++;
            if (!written_text(&writer)) {
                untimed_refused = true;
                cli_error("%s: record %" PRIu64 " (line %" PRIu64 ") has no time; %s needs "
                          "one: give every line a time, or convert to text (dfp-sim replay "
                          "reads untimed text directly)", in, rec.index, rec.position,
                          cap_format_name(writer.opt.format));
                break;
            }
            if (write_untimed_text(&writer, &rec) != 0) {
                write_failed = true;
                break;
            }
            continue;
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
    if (untimed_refused) {
        (void)remove(out); /* nothing usable: no half-converted file is left behind */
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
        if (untimed > 0) {
            printf(", %" PRIu64 " without a time (kept untimed)", untimed);
        }
        if (skipped_empty > 0) {
            printf(", %" PRIu64 " without octets left out", skipped_empty);
        }
        if (damaged > 0) {
            printf(", %" PRIu64 " damaged (reported above%s)", damaged,
                   damaged > CONVERT_MAX_REPORTED ? ", the first 10" : "");
        }
        printf("\n");
    }
    return rc < 0 ? 1 : 0;
}
