#ifndef DFP_SIM_COMMANDS_H
#define DFP_SIM_COMMANDS_H

int cmd_demo(int argc, char **argv);
int cmd_slave(int argc, char **argv);
int cmd_master(int argc, char **argv);
int cmd_inverter(int argc, char **argv);
int cmd_param(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_replay(int argc, char **argv);
int cmd_record(int argc, char **argv);

#endif
