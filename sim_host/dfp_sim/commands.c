/* Every command's option table, in the order of the help: what completion.c writes the shell
 * completions from and checks the help against. */
#include "commands.h"

/* check-cfg HEX takes no option (main.c reads its one operand). */
static const cli_command_t cli_check_cfg = {.name = "check-cfg"};

const cli_command_t *const cli_commands[] = {
    &cli_demo,    &cli_slave,  &cli_master, &cli_inverter,  &cli_param,
    &cli_convert, &cli_replay, &cli_record, &cli_line, &cli_monitor, &cli_check_cfg,
    &cli_gsd, &cli_conformance,
};
const size_t cli_n_commands = CLI_COUNT(cli_commands);
