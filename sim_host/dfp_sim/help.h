/* dfp-sim's usage text and its man page, both printed from the one table in help.c so that they
 * cannot drift apart; completion.c checks its options against the option tables. */
#ifndef DFP_SIM_HELP_H
#define DFP_SIM_HELP_H

#include <stdbool.h>
#include <stdio.h>

/* The whole text: usage forms, every command, the shared options, exit status, environment. */
void help_print_all(FILE *out);
/* One command's usage, the shared options it takes and the exit status. False, with nothing
 * printed, when cmd is no command. */
bool help_print_command(FILE *out, const char *cmd);
/* "demo, slave, ...": the commands in the order of the help, for error messages. */
const char *help_command_names(void);
/* For completion.c, which checks them against the option tables (cli_table.h): fn once per
 * command, in the order of the help, with the texts that name its options: texts[0] its
 * synopsis and text, then the term and the text of each shared option it takes. */
typedef void help_command_fn(void *ctx, const char *name, const char *const *texts, size_t n);
void help_each_command(help_command_fn *fn, void *ctx);
/* The same content as a man(7) page for section 1. */
void help_print_man(FILE *out, const char *version);

#endif
