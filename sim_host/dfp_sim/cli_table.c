/* The generic command-line reader of cli_table.h. */
#include "cli_table.h"

#include <stdio.h>
#include <string.h>

#include "cli.h"

const cli_opt_t *cli_find(const cli_command_t *cmd, const char *name, size_t *group)
{
    for (size_t g = 0; g < cmd->n_groups; g++) {
        for (size_t k = 0; k < cmd->groups[g].n; k++) {
            if (strcmp(cmd->groups[g].opts[k].name, name) == 0) {
                if (group != NULL) {
                    *group = g;
                }
                return &cmd->groups[g].opts[k];
            }
        }
    }
    return NULL;
}

/* v NULL (a table entry of a value kind without a placeholder): a bug of the table, told. */
static bool value_given(const cli_opt_t *o, const char *v)
{
    if (v == NULL) {
        cli_error("%s: the option table gives it no value (a bug of dfp-sim)", o->name);
        return false;
    }
    return true;
}

static bool set_choice(char *field, const cli_opt_t *o, const char *v)
{
    if (!value_given(o, v)) {
        return false;
    }
    for (const cli_choice_t *c = o->choices; c->word != NULL; c++) {
        if (strcmp(c->word, v) == 0) {
            int value = c->value;
            memcpy(field, &value, sizeof value);
            return true;
        }
    }
    cli_error(o->bad, v);
    return false;
}

/* A repeatable option's value: at most max of them, each 1..255 characters. */
static bool set_list(char *base, const cli_opt_t *o, const char *v)
{
    size_t *n = (size_t *)(void *)(base + o->aux);
    if (!value_given(o, v)) {
        return false;
    }
    if (*n == o->max || v[0] == '\0' || strlen(v) >= 256u) {
        cli_error("%s: at most %u of them, each 1..255 characters ('%s')", o->name, o->max, v);
        return false;
    }
    ((const char **)(void *)(base + o->at))[(*n)++] = v;
    return true;
}

/* "--report KIND FILE": the kind v, then the file from the next word. */
static bool set_kind_file(const char *cmd, char *base, const cli_opt_t *o, const char *v,
                          cli_args_t *args)
{
    if (!value_given(o, v)) {
        return false;
    }
    const cli_choice_t *kind = o->choices;
    while (kind->word != NULL && strcmp(kind->word, v) != 0) {
        kind++;
    }
    if (kind->word == NULL) {
        char use[200] = "";
        size_t n = 0;
        for (const cli_choice_t *c = o->choices; c->word != NULL; c++) {
            if (!c->alias) {
                n++;
            }
        }
        size_t k = 0;
        for (const cli_choice_t *c = o->choices; c->word != NULL; c++) {
            if (c->alias) {
                continue;
            }
            k++;
            const char *sep = k == 1u ? "" : k == n ? " or " : ", ";
            size_t used = strlen(use);
            (void)snprintf(use + used, sizeof use - used, "%s%s FILE", sep, c->word);
        }
        cli_error("%s: %s '%s': use %s", cmd, o->name, v, use);
        return false;
    }
    if (args->i + 1 >= args->argc) {
        cli_error("%s: %s %s: which file? %s %s FILE", cmd, o->name, v, o->name, v);
        return false;
    }
    size_t *count = (size_t *)(void *)(base + o->aux);
    if (*count == o->max) {
        /* "--report" gives "report files" */
        cli_error("%s: %s: at most %u %s files", cmd, o->name, o->max, o->name + 2);
        return false;
    }
    args->i++;
    cli_kind_file_t *files = (cli_kind_file_t *)(void *)(base + o->at);
    files[*count] = (cli_kind_file_t){kind->value, args->argv[args->i]};
    (*count)++;
    return true;
}

/* The value v (NULL for a flag) into the group's struct at base. False after reporting. */
static bool set_value(const char *cmd, char *base, const cli_opt_t *o, const char *v,
                      cli_args_t *args)
{
    char *field = base + o->at;
    if (o->seen != 0u) {
        *(bool *)(void *)(base + o->seen - 1u) = true;
    }
    switch (o->kind) {
    case CLI_FLAG:
        *(bool *)(void *)field = true;
        return true;
    case CLI_TEXT:
        *(const char **)(void *)field = v;
        return true;
    case CLI_U32:
        return cli_u32(o->name, v, o->min, o->max, (uint32_t *)(void *)field);
    case CLI_BAUD:
    case CLI_BAUD_AUTO:
        return cli_baud(o->name, v, o->kind == CLI_BAUD_AUTO, (uint32_t *)(void *)field);
    case CLI_HEX:
        return cli_hex(o->name, v, (uint8_t *)field, o->max, (size_t *)(void *)(base + o->aux));
    case CLI_CHOICE:
        return set_choice(field, o, v);
    case CLI_LIST:
        return set_list(base, o, v);
    case CLI_KIND_FILE:
        return set_kind_file(cmd, base, o, v, args);
    case CLI_CALL:
        return o->set(base, o, v, args);
    }
    return false;
}

/* Whether word, which is no option of the command, is an operand. */
static bool is_operand(const cli_command_t *cmd, const char *word)
{
    switch (cmd->operands) {
    case CLI_OPERANDS:
        return !(word[0] == '-' && word[1] != '\0');
    case CLI_OPERANDS_DD:
        return !(word[0] == '-' && word[1] == '-');
    case CLI_NO_OPERANDS:
        break;
    }
    return false;
}

int cli_parse(const cli_command_t *cmd, int argc, char **argv, void *opts)
{
    for (int i = 2; i < argc; i++) {
        size_t g = 0;
        const cli_opt_t *o = cli_find(cmd, argv[i], &g);
        if (o == NULL) {
            if (!is_operand(cmd, argv[i])) {
                cli_error("%s: unknown option '%s' (see dfp-sim --help)", cmd->name, argv[i]);
                return EXIT_USAGE;
            }
            if (!cmd->operand(opts, argv[i])) {
                return EXIT_USAGE;
            }
            continue;
        }
        const char *v = NULL;
        if (o->value != NULL && (v = cli_value(argc, argv, &i)) == NULL) {
            return EXIT_USAGE;
        }
        cli_args_t args = {argc, argv, i};
        if (!set_value(cmd->name, (char *)opts + cmd->groups[g].at, o, v, &args)) {
            return EXIT_USAGE;
        }
        i = args.i;
    }
    return 0;
}
