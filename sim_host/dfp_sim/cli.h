/* Command-line parsing shared by the dfp-sim subcommands. Every parse error prints one line
 * naming the option and the bad value, and the caller exits with status 2. */
#ifndef DFP_SIM_CLI_H
#define DFP_SIM_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define EXIT_USAGE 2

bool cli_u32(const char *opt, const char *text, uint32_t min, uint32_t max, uint32_t *out);
/* "F3F2", "F3 F2", "f3:f2", "0xF3,0xF2". */
bool cli_hex(const char *opt, const char *text, uint8_t *out, size_t max, size_t *len);
/* "auto" (0), or one of the ten PROFIBUS rates: 19200, 19.2k, 1.5M, 1500000 ... */
bool cli_baud(const char *opt, const char *text, bool allow_auto, uint32_t *out);
/* --address "4", "3-34", "3,5,7-9": distinct slave addresses 0..125, at most max of them.
 * Returns false after reporting, naming the option opt. */
bool cli_address_list(const char *opt, const char *text, uint8_t *out, size_t max, size_t *n);
/* For "--opt VALUE": returns argv[*i + 1] and advances, or reports the missing value. */
const char *cli_value(int argc, char **argv, int *i);
void cli_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* A file the command line names, with the option or operand that names it ("--capture",
 * "IN"); path NULL: not given. input: only read (a link there is followed); every other file is
 * written. */
typedef struct cli_file {
    const char *option;
    const char *path;
    bool input;
} cli_file_t;
/* Whether a and b are one file: the same name, the same device and inode when both exist, or,
 * when neither exists yet, the same name in the same directory ("new.ee", "./new.ee"). */
bool cli_same_file(const char *a, const char *b);
/* False after reporting "CMD: A and B are the same file (PATH_A, PATH_B): ..." when two of
 * files[0..n) are one file. For every command that writes a file the user names: opening it
 * would truncate another file of the same command line (an input, an EEPROM) before it is read. */
bool cli_files_distinct(const char *cmd, const cli_file_t *files, size_t n);
/* False after reporting "CMD: OPTION PATH is a symbolic link: refused ..." when a file of
 * files[0..n) that is written is a symbolic link (the files are opened without following one:
 * sim_fopen_write). cli_files_distinct checks this as well, after the same-file check. */
bool cli_no_links(const char *cmd, const cli_file_t *files, size_t n);
/* The log an LCM URL writes ("file://OUT.lcm?mode=w" or mode=a) into buf, else NULL. */
const char *cli_lcm_log_written(const char *url, char *buf, size_t n);

/* Set by SIGINT/SIGTERM once cli_catch_stop_signals() ran: a running command ends cleanly. */
extern volatile int cli_stop;
void cli_catch_stop_signals(void);

#endif
