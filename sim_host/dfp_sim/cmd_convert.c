/* dfp-sim convert: one capture file into another format or link type, record by record (so a
 * capture of any length converts in constant memory). The usual use: a PROFIBUS_DL (257) pcap,
 * which no Wireshark release maps, into USER0 (147) for the Lua dissector in tools/wireshark/,
 * or a text dump into pcapng and back. Damaged records are copied as they are and reported. */
#include <inttypes.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"
#include "report.h"

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

typedef struct convert_opts {
    const char *in;
    const char *out;
    cap_format_t in_format;
    const char *lcm_channel;
    cap_writer_options_t w;
    bool quiet;
} convert_opts_t;

static bool convert_operand(void *opts, const char *word)
{
    convert_opts_t *o = opts;
    if (o->in == NULL) {
        o->in = word;
    } else if (o->out == NULL) {
        o->out = word;
    } else {
        cli_error("convert takes two files, IN and OUT; '%s' is a third", word);
        return false;
    }
    return true;
}

static const cli_choice_t in_formats[] = {
    {"pcap", CAP_FORMAT_PCAP, false}, {"pcapng", CAP_FORMAT_PCAPNG, false},
    {"text", CAP_FORMAT_TEXT, false}, {"lcm", CAP_FORMAT_LCM, false},
    {NULL, 0, false}};

#define CONVERT(field) offsetof(convert_opts_t, field)

static const cli_opt_t convert_options[] = {
    {CLI_OPT("--format", "pcap|pcapng|text", CLI_CHOICE, CONVERT(w.format)),
     .choices = capture_format_words, .bad = "--format: '%s' is not one of pcap, pcapng, text"},
    {CLI_OPT("--linktype", "profibus|user0", CLI_CHOICE, CONVERT(w.linktype)),
     .choices = capture_linktype_words,
     .bad = "--linktype: '%s' is not profibus (257) or user0 (147)"},
    {CLI_OPT("--ns", NULL, CLI_FLAG, CONVERT(w.nanosecond))},
    {CLI_OPT("--in-format", "pcap|pcapng|text|lcm", CLI_CHOICE, CONVERT(in_format)),
     .choices = in_formats, .bad = "--in-format: '%s' is not one of pcap, pcapng, text, lcm"},
    {CLI_OPT("--channel", "NAME", CLI_TEXT, CONVERT(lcm_channel))},
    {CLI_OPT("--quiet", NULL, CLI_FLAG, CONVERT(quiet))},
};

static const cli_group_t convert_groups[] = {
    {convert_options, CLI_COUNT(convert_options), 0},
};

const cli_command_t cli_convert = {.name = "convert", .groups = convert_groups,
                                   .n_groups = CLI_COUNT(convert_groups),
                                   .operands = CLI_OPERANDS, .operand = convert_operand};

/* The command line into o: 0, or EXIT_USAGE after reporting. */
static int convert_parse(convert_opts_t *o, int argc, char **argv)
{
    *o = (convert_opts_t){.in_format = CAP_FORMAT_AUTO,
                          .w = {.format = CAP_FORMAT_AUTO, .linktype = 0}};
    if (cli_parse(&cli_convert, argc, argv, o) != 0) return EXIT_USAGE;
    if (o->in == NULL || o->out == NULL) {
        cli_error("convert needs an input and an output file: dfp-sim convert IN OUT");
        return EXIT_USAGE;
    }
    const cli_file_t files[] = {{"IN", o->in, .input = true}, {"OUT", o->out, false}};
    return cli_files_distinct("convert", files, 2u) ? 0 : EXIT_USAGE;
}

/* What the copy met on its way. */
typedef struct convert_counts {
    uint64_t damaged;
    uint64_t untimed;
    uint64_t skipped_empty;
    bool write_failed;
    bool untimed_refused;
} convert_counts_t;

/* One record into the writer: 0 to go on, -1 to stop (c says why). */
static int convert_record(const convert_opts_t *o, const cap_reader_t *reader,
                          cap_writer_t *writer, const cap_record_t *rec, convert_counts_t *c)
{
    if (rec->problem[0] != '\0') {
        c->damaged++;
        if (c->damaged <= CONVERT_MAX_REPORTED && !o->quiet) {
            (void)fprintf(stderr, "dfp-sim: %s: record %" PRIu64 " (%s %" PRIu64 "): %s\n",
                          o->in, rec->index, cap_position_unit(reader->format), rec->position,
                          rec->problem);
        }
    }
    if (rec->len == 0 && (reader->format == CAP_FORMAT_TEXT || written_text(writer))) {
        /* A text line that is no telegram, or an empty record text cannot show. */
        c->skipped_empty++;
        return 0;
    }
    if (!rec->has_time) {
        /* A text dump without times: text keeps it untimed (a bare hex line reads back
         * untimed); pcap and pcapng need a time, and an invented one would be taken for the
         * bus's timing by every later reader (replay infers the rate from it). */
        c->untimed++;
        if (!written_text(writer)) {
            c->untimed_refused = true;
            cli_error("%s: record %" PRIu64 " (line %" PRIu64 ") has no time; %s needs one: "
                      "give every line a time, or convert to text (dfp-sim replay reads "
                      "untimed text directly)", o->in, rec->index, rec->position,
                      cap_format_name(writer->opt.format));
            return -1;
        }
        c->write_failed = write_untimed_text(writer, rec) != 0;
        return c->write_failed ? -1 : 0;
    }
    c->write_failed = cap_writer_frame(writer, rec->t_ns, rec->data, rec->len, rec->dir) != 0;
    return c->write_failed ? -1 : 0;
}

static void print_summary(const convert_opts_t *o, cap_format_t in_fmt,
                          const cap_writer_options_t *written, uint64_t records,
                          const convert_counts_t *c)
{
    printf("%s (%s) -> %s (%s", o->in, cap_format_name(in_fmt), o->out,
           cap_format_name(written->format));
    if (written->format != CAP_FORMAT_TEXT) {
        printf(", link type %u, %s", written->linktype, written->nanosecond ? "ns" : "µs");
    }
    printf("): %" PRIu64 " records", records);
    if (c->untimed > 0) {
        printf(", %" PRIu64 " without a time (kept untimed)", c->untimed);
    }
    if (c->skipped_empty > 0) {
        printf(", %" PRIu64 " without octets left out", c->skipped_empty);
    }
    if (c->damaged > 0) {
        printf(", %" PRIu64 " damaged (reported above%s)", c->damaged,
               c->damaged > CONVERT_MAX_REPORTED ? ", the first 10" : "");
    }
    printf("\n");
}

int cmd_convert(int argc, char **argv)
{
    static convert_opts_t o;
    int rc = convert_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    static cap_reader_t reader;
    static cap_record_t rec;
    char err[1100];
    if (cap_reader_open_channel(&reader, o.in, o.in_format, o.lcm_channel, err, sizeof err) !=
        0) {
        cli_error("%s", err);
        return EXIT_USAGE;
    }
    if (reader.lcm_note[0] != '\0' && !o.quiet) {
        fprintf(stderr, "%s\n", reader.lcm_note);
    }
    /* The first record is read before the output is opened: its baud rate, when the input has
     * one, goes into the pcapng interface description. */
    rc = cap_reader_next(&reader, &rec);
    if (rc == 1) {
        o.w.baud = rec.baud;
    }
    if (o.w.linktype == 0 && reader.linktype != 0) {
        o.w.linktype = reader.linktype;
    }
    static cap_writer_t writer;
    if (cap_writer_open(&writer, o.out, &o.w, 0, err, sizeof err) != 0) {
        cli_error("%s", err);
        cap_reader_close(&reader);
        return 1;
    }
    convert_counts_t c = {0};
    for (; rc == 1; rc = cap_reader_next(&reader, &rec)) {
        if (convert_record(&o, &reader, &writer, &rec, &c) != 0) {
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
    if (cap_writer_close(&writer) != 0 || c.write_failed) {
        cli_error("could not write the whole capture to %s", o.out);
        return 1;
    }
    if (c.untimed_refused) {
        (void)remove(o.out); /* nothing usable: no half-converted file is left behind */
        return 1;
    }
    if (records == 0 && c.damaged > 0) {
        cli_error("%s: none of its %" PRIu64 " records is a telegram", o.in, c.damaged);
        return 2; /* not a capture at all: as replay says of the same file */
    }
    if (!o.quiet) {
        print_summary(&o, in_fmt, &written, records, &c);
    }
    return rc < 0 ? 1 : 0;
}
