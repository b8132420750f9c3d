/* The options of every dfp-sim command as tables: one table per command and one per shared
 * group (medium.h, instrument.h, report.h's capture options). cli_parse reads the command line
 * with them; completion.c writes the shell completions from them and checks that the help
 * names exactly the options they hold, so that no option is accepted without being documented
 * and completed, nor documented without being accepted. */
#ifndef DFP_SIM_CLI_TABLE_H
#define DFP_SIM_CLI_TABLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum cli_kind {
    CLI_FLAG,   /* bool at .at: true */
    CLI_TEXT,   /* const char * at .at: the value as given */
    CLI_U32,    /* uint32_t at .at: a number .min..max (cli_u32) */
    CLI_BAUD,   /* uint32_t at .at: a PROFIBUS rate (cli_baud) */
    CLI_BAUD_AUTO, /* the same, or "auto" (stored as 0) */
    CLI_HEX,    /* uint8_t[.max] at .at, its length (size_t) at .aux (cli_hex) */
    CLI_CHOICE, /* an int-sized field (an enum, uint32_t) at .at: the value of a word of
                 * .choices; another word is refused with .bad (printf, the word as %s) */
    CLI_LIST,   /* repeatable: const char *[.max] at .at, their count (size_t) at .aux */
    CLI_KIND_FILE, /* repeatable "--opt KIND FILE" (--report json FILE): cli_kind_file_t[.max]
                    * at .at, their count (size_t) at .aux; KIND a word of .choices */
    CLI_CALL,   /* .set does it */
} cli_kind_t;

typedef struct cli_choice {
    const char *word;
    int value;
    bool alias; /* accepted, but neither completed nor listed (257 for profibus) */
} cli_choice_t;

/* One "--opt KIND FILE" of a CLI_KIND_FILE option. */
typedef struct cli_kind_file {
    int kind; /* the value of KIND's word in .choices */
    const char *path;
} cli_kind_file_t;

/* The command line being read: argv[i] is the value just taken; a setter that takes further
 * words (--report json FILE) advances i. */
typedef struct cli_args {
    int argc;
    char **argv;
    int i;
} cli_args_t;

typedef struct cli_opt cli_opt_t;
/* value: NULL for an option without one (.value NULL). False after reporting. */
typedef bool cli_set_fn(void *base, const cli_opt_t *opt, const char *value, cli_args_t *args);

struct cli_opt {
    const char *name;  /* "--baud" */
    const char *value; /* the placeholder of the help ("RATE"), NULL: takes no value */
    cli_kind_t kind;
    size_t at;  /* offsetof the field in the group's struct */
    size_t aux; /* CLI_HEX, CLI_LIST: offsetof the length or count */
    uint32_t min, max;           /* CLI_U32 range; CLI_HEX, CLI_LIST: at most max */
    const cli_choice_t *choices; /* CLI_CHOICE, CLI_KIND_FILE, or for the completion of a
                                  * CLI_CALL */
    const char *bad;             /* CLI_CHOICE */
    cli_set_fn *set;             /* CLI_CALL */
    size_t seen; /* CLI_SEEN(type, field): a bool set whenever the option is given; 0: none */
};

/* The fields every option has, for an entry {CLI_OPT(...), .min = 1, ...}. */
#define CLI_OPT(name_, value_, kind_, at_) .name = (name_), .value = (value_), .kind = (kind_), \
                                          .at = (at_)
#define CLI_SEEN(type, field) (offsetof(type, field) + 1u)
#define CLI_COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* A table and where its struct lies in the command's options struct. */
typedef struct cli_group {
    const cli_opt_t *opts;
    size_t n;
    size_t at;
} cli_group_t;

typedef enum cli_operands {
    CLI_NO_OPERANDS, /* every word is an option */
    CLI_OPERANDS,    /* a word that is no option and not "-x..." is an operand ("-" is one) */
    CLI_OPERANDS_DD, /* a word that is no option and not "--..." is an operand (-5 is one) */
} cli_operands_t;

typedef struct cli_command {
    const char *name;
    const cli_group_t *groups;
    size_t n_groups;
    cli_operands_t operands;
    /* CLI_OPERANDS*: takes each operand in turn; false after reporting. */
    bool (*operand)(void *opts, const char *word);
    const char *words; /* the operands' literal words for the completion ("read write im0") */
} cli_command_t;

/* argv[2..] into opts (already holding the defaults). 0, or EXIT_USAGE after one line on
 * stderr: "CMD: unknown option 'X' (see dfp-sim --help)", "option X needs a value (see
 * dfp-sim --help)", or the bad value's own message (a CLI_KIND_FILE's: "CMD: --report 'xml':
 * use json FILE or junit FILE", "CMD: --report json: which file? --report json FILE", "CMD:
 * --report: at most 4 report files"). */
int cli_parse(const cli_command_t *cmd, int argc, char **argv, void *opts);
/* The option of cmd named name, NULL if none. */
const cli_opt_t *cli_find(const cli_command_t *cmd, const char *name, size_t *group);

/* Every command's table, in the order of the help (commands.c). */
extern const cli_command_t *const cli_commands[];
extern const size_t cli_n_commands;

#endif
