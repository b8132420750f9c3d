#ifndef DFP_SIM_COMMANDS_H
#define DFP_SIM_COMMANDS_H

#include "cli_table.h"

/* Each command's option table (cli_table.h), beside the command. */
extern const cli_command_t cli_demo, cli_slave, cli_master, cli_inverter, cli_param, cli_convert,
    cli_replay, cli_record, cli_line, cli_monitor, cli_gsd, cli_conformance;

int cmd_demo(int argc, char **argv);
int cmd_slave(int argc, char **argv);
int cmd_master(int argc, char **argv);
int cmd_inverter(int argc, char **argv);
int cmd_param(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_replay(int argc, char **argv);
int cmd_record(int argc, char **argv);
int cmd_line(int argc, char **argv);
int cmd_monitor(int argc, char **argv);
int cmd_gsd(int argc, char **argv);
int cmd_conformance(int argc, char **argv);

#endif
