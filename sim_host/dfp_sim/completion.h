/* dfp-sim --completion bash|zsh: the shell completion scripts, read from the help table (help.c)
 * so that a command or option added to the help completes without further work. */
#ifndef DFP_SIM_COMPLETION_H
#define DFP_SIM_COMPLETION_H

/* argv: dfp-sim --completion SHELL. Prints the script; 0, or 2 on a bad command line. */
int completion_main(int argc, char **argv);

#endif
