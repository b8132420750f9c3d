/* dfp-sim's option tables (sim_host/dfp_sim/cli_table.h): cli_parse with a table of every kind
 * (values stored, ranges, repeatable options and KIND FILE pairs, the exact error lines), the three ways a command
 * tells operands from options, and the check completion.c makes before writing the scripts:
 * a table that lacks an option its help names, or has one its help does not name, is refused. */
#include <fcntl.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "cli.h"
#include "cli_table.h"
#include "completion.h"

typedef struct opts {
    bool flag;
    bool seen;
    const char *text;
    uint32_t n;
    uint32_t baud;
    uint32_t baud_auto;
    uint8_t hex[4];
    size_t hex_len;
    int word;
    const char *list[2];
    size_t n_list;
    const char *pair[2];
    cli_kind_file_t reports[2];
    size_t n_reports;
    const char *operands[3];
    size_t n_operands;
} opts_t;

/* --pair A B: a setter that takes a second word. */
static bool set_pair(void *base, const cli_opt_t *opt, const char *value, cli_args_t *args)
{
    opts_t *o = base;
    if (args->i + 1 >= args->argc) {
        cli_error("%s %s: and the second?", opt->name, value);
        return false;
    }
    o->pair[0] = value;
    o->pair[1] = args->argv[++args->i];
    return true;
}

static bool take_operand(void *base, const char *word)
{
    opts_t *o = base;
    if (o->n_operands == 3u) {
        cli_error("t: '%s' is a fourth operand", word);
        return false;
    }
    o->operands[o->n_operands++] = word;
    return true;
}

static const cli_choice_t words[] = {
    {"red", 1, false}, {"green", 2, false}, {"rouge", 1, true}, {NULL, 0, false}};
static const cli_choice_t kinds[] = {
    {"json", 5, false}, {"junit", 6, false}, {"xunit", 6, true}, {"html", 7, false},
    {NULL, 0, false}};

#define AT(field) offsetof(opts_t, field)

static const cli_opt_t table[] = {
    {CLI_OPT("--flag", NULL, CLI_FLAG, AT(flag)), .seen = CLI_SEEN(opts_t, seen)},
    {CLI_OPT("--text", "T", CLI_TEXT, AT(text))},
    {CLI_OPT("--n", "N", CLI_U32, AT(n)), .min = 3, .max = 125},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, AT(baud))},
    {CLI_OPT("--baud-auto", "RATE|auto", CLI_BAUD_AUTO, AT(baud_auto))},
    {CLI_OPT("--hex", "HEX", CLI_HEX, AT(hex)), .aux = AT(hex_len), .max = 4},
    {CLI_OPT("--word", "red|green", CLI_CHOICE, AT(word)), .choices = words,
     .bad = "t: --word '%s': use red or green"},
    {CLI_OPT("--list", "NAME", CLI_LIST, AT(list)), .aux = AT(n_list), .max = 2},
    {CLI_OPT("--pair", "A B", CLI_CALL, 0), .set = set_pair},
    {CLI_OPT("--report", "json|junit|html FILE", CLI_KIND_FILE, AT(reports)),
     .aux = AT(n_reports), .max = 2, .choices = kinds},
};

static const cli_group_t groups[] = {{table, CLI_COUNT(table), 0}};

static const cli_command_t no_operands = {.name = "t", .groups = groups, .n_groups = 1};
static const cli_command_t operands = {.name = "t", .groups = groups, .n_groups = 1,
                                       .operands = CLI_OPERANDS, .operand = take_operand};
static const cli_command_t operands_dd = {.name = "t", .groups = groups, .n_groups = 1,
                                          .operands = CLI_OPERANDS_DD, .operand = take_operand};

static char err[512];

/* cli_parse on "dfp-sim t ARGS..." (NULL-terminated) into *o; stderr into err. */
static int parse(const cli_command_t *c, opts_t *o, const char *const *args)
{
    char *argv[32] = {"dfp-sim", "t"};
    int argc = 2;
    for (; args[argc - 2] != NULL; argc++) {
        argv[argc] = (char *)(uintptr_t)args[argc - 2];
    }
    memset(o, 0, sizeof *o);
    fflush(stderr);
    int saved = dup(2);
    FILE *tmp = tmpfile();
    dup2(fileno(tmp), 2);
    int rc = cli_parse(c, argc, argv, o);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(tmp);
    size_t n = fread(err, 1, sizeof err - 1u, tmp);
    err[n] = '\0';
    fclose(tmp);
    return rc;
}

#define ARGS(...) ((const char *const[]){__VA_ARGS__, NULL})

static void test_values(void)
{
    check_test_name_ = "values";
    opts_t o;
    CHECK_EQ(parse(&no_operands, &o,
                   ARGS("--flag", "--text", "-x", "--n", "0x10", "--baud", "1.5M", "--baud-auto",
                        "auto", "--hex", "F3:f2", "--word", "green", "--list", "a", "--list",
                        "b", "--pair", "p", "q")),
             0);
    CHECK_STR(err, "");
    CHECK(o.flag && o.seen);
    CHECK_STR(o.text, "-x"); /* a value may start with a dash: it is taken as given */
    CHECK_EQ(o.n, 16);
    CHECK_EQ(o.baud, 1500000);
    CHECK_EQ(o.baud_auto, 0);
    CHECK_EQ(o.hex_len, 2);
    CHECK_EQ(o.hex[0], 0xF3);
    CHECK_EQ(o.hex[1], 0xF2);
    CHECK_EQ(o.word, 2);
    CHECK_EQ(o.n_list, 2);
    CHECK_STR(o.list[1], "b");
    CHECK_STR(o.pair[0], "p");
    CHECK_STR(o.pair[1], "q");
    /* KIND FILE: the file may look like an option or a kind */
    CHECK_EQ(parse(&no_operands, &o, ARGS("--report", "html", "--flag", "--report", "xunit",
                                          "json")),
             0);
    CHECK_EQ(o.n_reports, 2);
    CHECK_EQ(o.reports[0].kind, 7);
    CHECK_STR(o.reports[0].path, "--flag");
    CHECK(!o.flag);
    CHECK_EQ(o.reports[1].kind, 6); /* an alias */
    CHECK_STR(o.reports[1].path, "json");
    CHECK_EQ(parse(&no_operands, &o, ARGS("--word", "rouge", "--n", "3", "--n", "125")), 0);
    CHECK_EQ(o.word, 1); /* an alias */
    CHECK_EQ(o.n, 125);  /* the last one given */
    CHECK(!o.seen);
}

/* Each failure: exit status 2 and exactly this line. */
static void expect_error(const cli_command_t *c, const char *const *args, const char *line)
{
    opts_t o;
    CHECK_EQ(parse(c, &o, args), EXIT_USAGE);
    char want[600];
    (void)snprintf(want, sizeof want, "dfp-sim: %s\n", line);
    CHECK_STR(err, want);
}

static void test_errors(void)
{
    check_test_name_ = "errors";
    expect_error(&no_operands, ARGS("--nope"), "t: unknown option '--nope' (see dfp-sim --help)");
    /* no --opt=value syntax: the old parsers compared whole words */
    expect_error(&no_operands, ARGS("--n=5"), "t: unknown option '--n=5' (see dfp-sim --help)");
    expect_error(&no_operands, ARGS("--fla"), "t: unknown option '--fla' (see dfp-sim --help)");
    expect_error(&no_operands, ARGS("--n"), "option --n needs a value (see dfp-sim --help)");
    expect_error(&no_operands, ARGS("--flag", "--text"),
                 "option --text needs a value (see dfp-sim --help)");
    expect_error(&no_operands, ARGS("--n", "2"), "--n: '2' is not a number from 3 to 125");
    expect_error(&no_operands, ARGS("--n", "126"), "--n: '126' is not a number from 3 to 125");
    expect_error(&no_operands, ARGS("--n", "-4"), "--n: '-4' is not a number from 3 to 125");
    expect_error(&no_operands, ARGS("--baud", "auto"),
                 "--baud: 'auto' is not a PROFIBUS rate (9600 19200 45450 93750 187500 500000 "
                 "1.5M 3M 6M 12M)");
    expect_error(&no_operands, ARGS("--baud-auto", "2M"),
                 "--baud-auto: '2M' is not a PROFIBUS rate (9600 19200 45450 93750 187500 500000 "
                 "1.5M 3M 6M 12M or auto)");
    expect_error(&no_operands, ARGS("--hex", "0102030405"), "--hex: more than 4 octets");
    expect_error(&no_operands, ARGS("--hex", "F"),
                 "--hex: 'F' is not a sequence of hex octets (e.g. F3F2)");
    expect_error(&no_operands, ARGS("--word", "blue"), "t: --word 'blue': use red or green");
    expect_error(&no_operands, ARGS("--list", "a", "--list", "b", "--list", "c"),
                 "--list: at most 2 of them, each 1..255 characters ('c')");
    expect_error(&no_operands, ARGS("--list", ""),
                 "--list: at most 2 of them, each 1..255 characters ('')");
    expect_error(&no_operands, ARGS("--pair", "p"), "--pair p: and the second?");
    /* the kinds named from the table, its alias not */
    expect_error(&no_operands, ARGS("--report", "xml", "f"),
                 "t: --report 'xml': use json FILE, junit FILE or html FILE");
    expect_error(&no_operands, ARGS("--report", "json"),
                 "t: --report json: which file? --report json FILE");
    expect_error(&no_operands, ARGS("--report"),
                 "option --report needs a value (see dfp-sim --help)");
    expect_error(&no_operands,
                 ARGS("--report", "json", "a", "--report", "json", "b", "--report", "html", "c"),
                 "t: --report: at most 2 report files");
}

static void test_operands(void)
{
    check_test_name_ = "operands";
    opts_t o;
    expect_error(&no_operands, ARGS("in"), "t: unknown option 'in' (see dfp-sim --help)");
    CHECK_EQ(parse(&operands, &o, ARGS("in", "--flag", "-", "out")), 0);
    CHECK_EQ(o.n_operands, 3);
    CHECK_STR(o.operands[1], "-"); /* standard input or output */
    CHECK(o.flag);
    expect_error(&operands, ARGS("in", "-5"), "t: unknown option '-5' (see dfp-sim --help)");
    expect_error(&operands, ARGS("a", "b", "c", "d"), "t: 'd' is a fourth operand");
    CHECK_EQ(parse(&operands_dd, &o, ARGS("write", "-5", "-")), 0); /* a negative VALUE */
    CHECK_STR(o.operands[1], "-5");
    expect_error(&operands_dd, ARGS("write", "--5"),
                 "t: unknown option '--5' (see dfp-sim --help)");
}

/* ---- the help against the tables (completion.c) ---- */

/* demo's options as its help names them, and one more the help does not have. */
static const cli_opt_t demo_all[] = {
    {CLI_OPT("--capture", "FILE", CLI_TEXT, 0)},
    {CLI_OPT("--capture-format", "F", CLI_TEXT, 0)},
    {CLI_OPT("--capture-linktype", "L", CLI_TEXT, 0)},
    {CLI_OPT("--capture-ns", NULL, CLI_FLAG, 0)},
    {CLI_OPT("--lcm", "URL", CLI_TEXT, 0)},
    {CLI_OPT("--http", "PORT", CLI_TEXT, 0)},
    {CLI_OPT("--http-token-file", "FILE", CLI_TEXT, 0)},
    {CLI_OPT("--http-viewer-token-file", "FILE", CLI_TEXT, 0)},
    {CLI_OPT("--http-no-auth", NULL, CLI_FLAG, 0)},
    {CLI_OPT("--http-allow-host", "NAME", CLI_TEXT, 0)},
    {CLI_OPT("--http-allow-origin", "ORIGIN", CLI_TEXT, 0)},
    {CLI_OPT("--http-cert", "FILE", CLI_TEXT, 0)},
    {CLI_OPT("--http-key", "FILE", CLI_TEXT, 0)},
    {CLI_OPT("--quiet", NULL, CLI_FLAG, 0)},
    {CLI_OPT("--log-level", "L", CLI_TEXT, 0)},
    {CLI_OPT("--timestamps", "T", CLI_TEXT, 0)},
    {CLI_OPT("--not-in-help", NULL, CLI_FLAG, 0)},
};

static cli_group_t demo_groups[] = {{demo_all, CLI_COUNT(demo_all), 0}};
static const cli_command_t demo = {.name = "demo", .groups = demo_groups, .n_groups = 1};
const cli_command_t *const cli_commands[] = {&demo};
const size_t cli_n_commands = 1;

static int completion(void)
{
    char *argv[] = {"dfp-sim", "--completion", "bash", NULL};
    fflush(stderr);
    fflush(stdout);
    int saved_err = dup(2);
    int saved_out = dup(1);
    FILE *tmp = tmpfile();
    int null = open("/dev/null", O_WRONLY);
    dup2(fileno(tmp), 2);
    dup2(null, 1);
    int rc = completion_main(3, argv);
    fflush(stderr);
    fflush(stdout);
    dup2(saved_err, 2);
    dup2(saved_out, 1);
    close(saved_err);
    close(saved_out);
    close(null);
    rewind(tmp);
    size_t n = fread(err, 1, sizeof err - 1u, tmp);
    err[n] = '\0';
    fclose(tmp);
    return rc;
}

static void test_help_agrees(void)
{
    check_test_name_ = "help against tables";
    CHECK_EQ(completion(), 1);
    CHECK_STR(err, "dfp-sim: --completion: demo takes --not-in-help, which its help does not "
                   "name\n");
    demo_groups[0].n = CLI_COUNT(demo_all) - 1u; /* the table as the help has it */
    CHECK_EQ(completion(), 1);                   /* but the help has more commands */
    CHECK_STR(err, "dfp-sim: --completion: slave is in the help but has no option table\n");
    demo_groups[0].n = 3; /* --capture-ns, --lcm ... missing */
    CHECK_EQ(completion(), 1);
    CHECK_STR(err, "dfp-sim: --completion: the help of demo names --lcm, which its option table "
                   "does not have\n");
}

int main(void)
{
    test_values();
    test_errors();
    test_operands();
    test_help_agrees();
    return check_report();
}
