/* The bash and zsh completion scripts, written from the option tables (cli_table.h): each
 * command's options, the words of those that take one of a list (--via channel|movilink|...),
 * and the literal operands of param (read, write, im0). Before writing, the help (help.c) is
 * checked against the tables: every --option the help names for a command must be in its table,
 * and every option of the table must be named in its help. The build writes the scripts and the
 * man page with dfp-sim, so an option cannot be added to one side alone. */
#include "completion.h"

#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cli_table.h"
#include "help.h"

#define MAX_OPTIONS 64

/* ---- the help against the tables ---- */

typedef struct agree {
    char error[200]; /* empty: they agree so far */
    size_t commands; /* commands of the help seen */
} agree_t;

static const cli_command_t *table_of(const char *name)
{
    for (size_t i = 0; i < cli_n_commands; i++) {
        if (strcmp(cli_commands[i]->name, name) == 0) {
            return cli_commands[i];
        }
    }
    return NULL;
}

/* The option's place among all the command's options (the seen[] index of check_command). */
static size_t option_index(const cli_command_t *c, const cli_opt_t *o)
{
    size_t n = 0;
    for (size_t g = 0; g < c->n_groups; g++) {
        if (o >= c->groups[g].opts && o < c->groups[g].opts + c->groups[g].n) {
            return n + (size_t)(o - c->groups[g].opts);
        }
        n += c->groups[g].n;
    }
    return n;
}

/* Every "--name" of text (after a space, a bracket, a bar or a parenthesis) into seen[];
 * false, with a->error set, on one the table does not have. */
static bool scan_text(agree_t *a, const cli_command_t *c, const char *text, bool *seen)
{
    for (const char *p = strstr(text, "--"); p != NULL; p = strstr(p + 2, "--")) {
        if (p != text && strchr(" \n[|(\"", p[-1]) == NULL) {
            continue;
        }
        size_t n = 2u + strspn(p + 2, "abcdefghijklmnopqrstuvwxyz0123456789-");
        while (n > 2u && p[n - 1u] == '-') {
            n--;
        }
        char name[40];
        if (n == 2u || n >= sizeof name) {
            continue;
        }
        (void)snprintf(name, sizeof name, "%.*s", (int)n, p);
        const cli_opt_t *o = cli_find(c, name, NULL);
        if (o == NULL) {
            (void)snprintf(a->error, sizeof a->error,
                           "the help of %s names %s, which its option table does not have",
                           c->name, name);
            return false;
        }
        seen[option_index(c, o)] = true;
    }
    return true;
}

static void check_command(void *ctx, const char *name, const char *const *texts, size_t n)
{
    agree_t *a = ctx;
    const cli_command_t *c = table_of(name);
    a->commands++;
    if (a->error[0] != '\0') {
        return;
    }
    if (c == NULL) {
        (void)snprintf(a->error, sizeof a->error, "%s is in the help but has no option table",
                       name);
        return;
    }
    bool seen[MAX_OPTIONS] = {false};
    for (size_t i = 0; i < n; i++) {
        if (!scan_text(a, c, texts[i], seen)) {
            return;
        }
    }
    for (size_t g = 0, k = 0; g < c->n_groups; g++) {
        for (size_t j = 0; j < c->groups[g].n; j++, k++) {
            if (k >= MAX_OPTIONS || !seen[k]) {
                (void)snprintf(a->error, sizeof a->error,
                               "%s takes %s, which its help does not name", name,
                               c->groups[g].opts[j].name);
                return;
            }
        }
    }
}

/* NULL when the help and the tables agree, else what differs (in buf). */
static const char *help_disagrees(agree_t *a)
{
    memset(a, 0, sizeof *a);
    help_each_command(check_command, a);
    if (a->error[0] == '\0' && a->commands != cli_n_commands) {
        (void)snprintf(a->error, sizeof a->error, "the help has %zu commands, the tables %zu",
                       a->commands, cli_n_commands);
    }
    return a->error[0] != '\0' ? a->error : NULL;
}

/* ---- the scripts ---- */

static void print_names(FILE *out)
{
    for (size_t i = 0; i < cli_n_commands; i++) {
        fprintf(out, "%s%s", i > 0u ? " " : "", cli_commands[i]->name);
    }
}

static void print_options(FILE *out, const cli_command_t *c)
{
    for (size_t g = 0; g < c->n_groups; g++) {
        for (size_t k = 0; k < c->groups[g].n; k++) {
            fprintf(out, "%s ", c->groups[g].opts[k].name);
        }
    }
    fputs("--help", out);
}

/* The case patterns "cmd:--opt|cmd:--opt2" of the options that take any value (a file name, a
 * number): there the shell's own completion (file names) applies. */
static bool print_free_values(FILE *out, const char *indent)
{
    bool any = false;
    for (size_t i = 0; i < cli_n_commands; i++) {
        const cli_command_t *c = cli_commands[i];
        for (size_t g = 0; g < c->n_groups; g++) {
            for (size_t k = 0; k < c->groups[g].n; k++) {
                const cli_opt_t *o = &c->groups[g].opts[k];
                if (o->value != NULL && o->choices == NULL) {
                    fprintf(out, "%s%s:%s", any ? "|" : indent, c->name, o->name);
                    any = true;
                }
            }
        }
    }
    return any;
}

/* One case branch per option with a list of values; fmt gets "cmd", "--opt" and the list. */
static void print_choices(FILE *out, const char *fmt)
{
    for (size_t i = 0; i < cli_n_commands; i++) {
        const cli_command_t *c = cli_commands[i];
        for (size_t g = 0; g < c->n_groups; g++) {
            for (size_t k = 0; k < c->groups[g].n; k++) {
                const cli_opt_t *o = &c->groups[g].opts[k];
                char words[160] = "";
                size_t n = 0;
                for (const cli_choice_t *w = o->choices; w != NULL && w->word != NULL; w++) {
                    if (!w->alias && n < sizeof words) {
                        n += (size_t)snprintf(words + n, sizeof words - n, "%s%s",
                                              n > 0u ? " " : "", w->word);
                    }
                }
                if (n > 0u) {
                    fprintf(out, fmt, c->name, o->name, words);
                }
            }
        }
    }
}

static void print_bash(FILE *out)
{
    fputs("# bash completion for dfp-sim: its commands, each command's options and the values some\n"
          "# of them take, from its help table (written by dfp-sim --completion bash).\n"
          "_dfp_sim()\n{\n"
          "    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} opts= words= w\n"
          "    COMPREPLY=()\n"
          "    if [ \"$COMP_CWORD\" -eq 1 ]; then\n"
          "        mapfile -t COMPREPLY < <(compgen -W '", out);
    print_names(out);
    fputs(" help --help --version' -- \"$cur\")\n        return 0\n    fi\n"
          "    case ${COMP_WORDS[1]} in\n"
          "    help)\n        [ \"$COMP_CWORD\" -eq 2 ] && mapfile -t COMPREPLY < <(compgen -W '", out);
    print_names(out);
    fputs("' -- \"$cur\")\n        return 0 ;;\n", out);
    for (size_t i = 0; i < cli_n_commands; i++) {
        const cli_command_t *c = cli_commands[i];
        fprintf(out, "    %s) opts='", c->name);
        print_options(out, c);
        fprintf(out, "'; words='%s' ;;\n", c->words != NULL ? c->words : "");
    }
    fputs("    *) return 0 ;;\n    esac\n    case ${COMP_WORDS[1]}:$prev in\n", out);
    print_choices(out, "    %s:%s) mapfile -t COMPREPLY < <(compgen -W '%s' -- \"$cur\"); return 0 ;;\n");
    if (print_free_values(out, "    ")) {
        fputs(") return 0 ;; # a file, a number ...: readline's default\n", out);
    }
    fputs("    esac\n"
          "    if [[ $cur == -* ]]; then\n"
          "        mapfile -t COMPREPLY < <(compgen -W \"$opts\" -- \"$cur\")\n"
          "    elif [ -n \"$words\" ]; then\n"
          "        for w in \"${COMP_WORDS[@]:2:COMP_CWORD-2}\"; do\n"
          "            [[ \" $words \" == *\" $w \"* ]] && return 0\n"
          "        done\n"
          "        mapfile -t COMPREPLY < <(compgen -W \"$words\" -- \"$cur\")\n"
          "    fi\n    return 0\n}\n"
          "complete -F _dfp_sim -o default dfp-sim\n", out);
}

static void print_zsh(FILE *out)
{
    fputs("#compdef dfp-sim\n"
          "# zsh completion for dfp-sim: its commands, each command's options and the values some\n"
          "# of them take, from its help table (written by dfp-sim --completion zsh).\n"
          "local cur=${words[CURRENT]} prev=${words[CURRENT-1]} w\n"
          "local -a opts pos\n"
          "if (( CURRENT == 2 )); then\n    compadd -- ", out);
    print_names(out);
    fputs(" help --help --version\n    return\nfi\n"
          "case ${words[2]} in\n"
          "help) (( CURRENT == 3 )) && compadd -- ", out);
    print_names(out);
    fputs("; return ;;\n", out);
    for (size_t i = 0; i < cli_n_commands; i++) {
        const cli_command_t *c = cli_commands[i];
        fprintf(out, "%s) opts=(", c->name);
        print_options(out, c);
        fprintf(out, "); pos=(%s) ;;\n", c->words != NULL ? c->words : "");
    }
    fputs("*) _files; return ;;\nesac\ncase ${words[2]}:$prev in\n", out);
    print_choices(out, "%s:%s) compadd -- %s; return ;;\n");
    if (print_free_values(out, "")) {
        fputs(") _files; return ;;\n", out);
    }
    fputs("esac\n"
          "if [[ $cur == -* ]]; then\n    compadd -- $opts\n    return\nfi\n"
          "for w in ${words[3,CURRENT-1]}; do\n"
          "    (( ${pos[(Ie)$w]} )) && { _files; return; }\n"
          "done\n"
          "(( $#pos )) && compadd -- $pos || _files\n", out);
}

int completion_main(int argc, char **argv)
{
    bool bash = argc == 3 && strcmp(argv[2], "bash") == 0;
    bool zsh = argc == 3 && strcmp(argv[2], "zsh") == 0;
    if (!bash && !zsh) {
        cli_error("--completion takes one shell: bash or zsh");
        return EXIT_USAGE;
    }
    agree_t agree;
    const char *differ = help_disagrees(&agree);
    if (differ != NULL) {
        cli_error("--completion: %s", differ);
        return 1;
    }
    if (bash) {
        print_bash(stdout);
    } else {
        print_zsh(stdout);
    }
    return 0;
}
