/* The bash and zsh completion scripts, read from the help table: each command's options are the
 * --words of its synopsis and of the shared options it takes; an option followed by a value
 * placeholder takes a value, and by a list of plain words (--via channel|movilink|...) takes one
 * of them; the plain words of a synopsis outside an option (param's read, write, im0) are its
 * positional words. The build writes the scripts with this, so they cannot drift from the help. */
#include "completion.h"

#include <ctype.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "help.h"

#define MAX_COMMANDS 16
#define MAX_OPTIONS 48
#define NAME_LEN 32
#define LIST_LEN 96

typedef struct {
    char name[NAME_LEN];
    bool takes_value;
    char choices[LIST_LEN]; /* "a b c", or empty: any value */
} comp_option_t;

typedef struct {
    char name[NAME_LEN];
    comp_option_t options[MAX_OPTIONS];
    size_t n_options;
    char words[LIST_LEN]; /* positional words, "a b c" */
} comp_command_t;

typedef struct {
    comp_command_t commands[MAX_COMMANDS];
    size_t n;
    const char *error; /* a limit above was too small: the table outgrew this file */
} comp_table_t;

/* ---- reading the help table ---- */

/* "--name" at the start of s (lower case, digits, inner dashes): its length, else 0. */
static size_t option_len(const char *s, size_t len)
{
    if (len < 3u || s[0] != '-' || s[1] != '-' || !isalnum((unsigned char)s[2])) {
        return 0;
    }
    size_t n = 2;
    while (n < len && (islower((unsigned char)s[n]) || isdigit((unsigned char)s[n]) || s[n] == '-')) {
        n++;
    }
    while (s[n - 1u] == '-') {
        n--;
    }
    return n;
}

/* A word typed as printed (channel, user0, 1.5), not a placeholder (FILE, [ADDR:]PORT). */
static bool is_literal(const char *s, size_t len)
{
    if (len == 0u || !(islower((unsigned char)s[0]) || isdigit((unsigned char)s[0]))) {
        return false;
    }
    for (size_t i = 0; i < len; i++) {
        if (!(islower((unsigned char)s[i]) || isdigit((unsigned char)s[i]) || s[i] == '.')) {
            return false;
        }
    }
    return true;
}

static void list_add(comp_table_t *t, char *list, const char *s, size_t len)
{
    size_t used = strlen(list);
    if (used + len + 2u > LIST_LEN) {
        t->error = "a list of words is too long";
        return;
    }
    (void)snprintf(list + used, LIST_LEN - used, "%s%.*s", used > 0u ? " " : "", (int)len, s);
}

static comp_option_t *add_option(comp_table_t *t, comp_command_t *c, const char *s, size_t len)
{
    for (size_t i = 0; i < c->n_options; i++) {
        if (strlen(c->options[i].name) == len && strncmp(c->options[i].name, s, len) == 0) {
            return &c->options[i];
        }
    }
    if (c->n_options == MAX_OPTIONS || len >= NAME_LEN) {
        t->error = "too many options or too long a name";
        return NULL;
    }
    comp_option_t *o = &c->options[c->n_options++];
    (void)snprintf(o->name, sizeof o->name, "%.*s", (int)len, s);
    return o;
}

/* One token of a text ("[--via", "channel|movilink]", "DEV|--bus"). value_of: the option just
 * before it that may take it as its value. Returns the option that may take the next token. */
static comp_option_t *read_token(comp_table_t *t, comp_command_t *c, bool synopsis,
                                 comp_option_t *value_of, const char *p, size_t len)
{
    /* Brackets mark optional parts; only those at the ends of a token are syntax
     * (can:IFACE[:ADDR] keeps its inner one). */
    while (len > 0u && p[0] == '[') {
        p++;
        len--;
    }
    bool closed = false;
    while (len > 0u && p[len - 1u] == ']') {
        len--;
        closed = true;
    }
    const char *alt[16];
    size_t alt_len[16];
    size_t n = 0;
    for (size_t start = 0, i = 0; i <= len && n < 16u; i++) {
        if (i == len || p[i] == '|') {
            alt[n] = p + start;
            alt_len[n++] = i - start;
            start = i + 1u;
        }
    }
    comp_option_t *next = NULL;
    bool plain = true; /* every alternative a literal word */
    for (size_t i = 0; i < n; i++) {
        size_t ol = option_len(alt[i], alt_len[i]);
        if (ol > 0u) {
            comp_option_t *o = add_option(t, c, alt[i], ol);
            /* "--capture-ns:" in a sentence or "[--verbose]" take nothing */
            next = (ol == alt_len[i] && !closed && i + 1u == n) ? o : NULL;
            plain = false;
        } else if (!is_literal(alt[i], alt_len[i])) {
            plain = false;
        }
    }
    bool value_like = len > 0u && (isalnum((unsigned char)p[0]) || p[0] == '.');
    if (value_of != NULL && value_like && option_len(alt[0], alt_len[0]) == 0u) {
        value_of->takes_value = true;
        if (plain && n >= 2u && value_of->choices[0] == '\0') {
            for (size_t i = 0; i < n; i++) {
                list_add(t, value_of->choices, alt[i], alt_len[i]);
            }
        }
    } else if (synopsis && value_of == NULL && plain && n == 1u && isalpha((unsigned char)p[0])) {
        list_add(t, c->words, p, len);
    }
    return next;
}

static void read_text(comp_table_t *t, comp_command_t *c, const char *text, bool synopsis)
{
    comp_option_t *pending = NULL;
    for (const char *p = text; *p != '\0';) {
        while (*p == ' ' || *p == '\n') {
            p++;
        }
        size_t len = strcspn(p, " \n");
        if (len > 0u) {
            pending = read_token(t, c, synopsis, pending, p, len);
        }
        p += len;
    }
}

static void read_command(void *ctx, const char *name, const char *const *texts, size_t n)
{
    comp_table_t *t = ctx;
    if (t->n == MAX_COMMANDS || strlen(name) >= NAME_LEN) {
        t->error = "too many commands";
        return;
    }
    comp_command_t *c = &t->commands[t->n++];
    (void)snprintf(c->name, sizeof c->name, "%s", name);
    for (size_t i = 0; i < n; i++) {
        read_text(t, c, texts[i], i == 0u);
    }
    (void)add_option(t, c, "--help", strlen("--help"));
}

/* ---- the scripts ---- */

static void print_names(FILE *out, const comp_table_t *t)
{
    for (size_t i = 0; i < t->n; i++) {
        fprintf(out, "%s%s", i > 0u ? " " : "", t->commands[i].name);
    }
}

static void print_options(FILE *out, const comp_command_t *c)
{
    for (size_t i = 0; i < c->n_options; i++) {
        fprintf(out, "%s%s", i > 0u ? " " : "", c->options[i].name);
    }
}

/* The case patterns "cmd:--opt|cmd:--opt2" of the options that take any value (a file name, a
 * number): there the shell's own completion (file names) applies. */
static bool print_free_values(FILE *out, const comp_table_t *t, const char *indent)
{
    bool any = false;
    for (size_t i = 0; i < t->n; i++) {
        const comp_command_t *c = &t->commands[i];
        for (size_t k = 0; k < c->n_options; k++) {
            if (c->options[k].takes_value && c->options[k].choices[0] == '\0') {
                fprintf(out, "%s%s:%s", any ? "|" : indent, c->name, c->options[k].name);
                any = true;
            }
        }
    }
    return any;
}

/* One case branch per option with a list of values; fmt gets "cmd:--opt" and the list. */
static void print_choices(FILE *out, const comp_table_t *t, const char *fmt)
{
    for (size_t i = 0; i < t->n; i++) {
        const comp_command_t *c = &t->commands[i];
        for (size_t k = 0; k < c->n_options; k++) {
            if (c->options[k].choices[0] != '\0') {
                fprintf(out, fmt, c->name, c->options[k].name, c->options[k].choices);
            }
        }
    }
}

static void print_bash(FILE *out, const comp_table_t *t)
{
    fputs("# bash completion for dfp-sim: its commands, each command's options and the values some\n"
          "# of them take, from its help table (written by dfp-sim --completion bash).\n"
          "_dfp_sim()\n{\n"
          "    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} opts= words= w\n"
          "    COMPREPLY=()\n"
          "    if [ \"$COMP_CWORD\" -eq 1 ]; then\n"
          "        mapfile -t COMPREPLY < <(compgen -W '", out);
    print_names(out, t);
    fputs(" help --help --version' -- \"$cur\")\n        return 0\n    fi\n"
          "    case ${COMP_WORDS[1]} in\n"
          "    help)\n        [ \"$COMP_CWORD\" -eq 2 ] && mapfile -t COMPREPLY < <(compgen -W '", out);
    print_names(out, t);
    fputs("' -- \"$cur\")\n        return 0 ;;\n", out);
    for (size_t i = 0; i < t->n; i++) {
        fprintf(out, "    %s) opts='", t->commands[i].name);
        print_options(out, &t->commands[i]);
        fprintf(out, "'; words='%s' ;;\n", t->commands[i].words);
    }
    fputs("    *) return 0 ;;\n    esac\n    case ${COMP_WORDS[1]}:$prev in\n", out);
    print_choices(out, t, "    %s:%s) mapfile -t COMPREPLY < <(compgen -W '%s' -- \"$cur\"); return 0 ;;\n");
    if (print_free_values(out, t, "    ")) {
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

static void print_zsh(FILE *out, const comp_table_t *t)
{
    fputs("#compdef dfp-sim\n"
          "# zsh completion for dfp-sim: its commands, each command's options and the values some\n"
          "# of them take, from its help table (written by dfp-sim --completion zsh).\n"
          "local cur=${words[CURRENT]} prev=${words[CURRENT-1]} w\n"
          "local -a opts pos\n"
          "if (( CURRENT == 2 )); then\n    compadd -- ", out);
    print_names(out, t);
    fputs(" help --help --version\n    return\nfi\n"
          "case ${words[2]} in\n"
          "help) (( CURRENT == 3 )) && compadd -- ", out);
    print_names(out, t);
    fputs("; return ;;\n", out);
    for (size_t i = 0; i < t->n; i++) {
        fprintf(out, "%s) opts=(", t->commands[i].name);
        print_options(out, &t->commands[i]);
        fprintf(out, "); pos=(%s) ;;\n", t->commands[i].words);
    }
    fputs("*) _files; return ;;\nesac\ncase ${words[2]}:$prev in\n", out);
    print_choices(out, t, "%s:%s) compadd -- %s; return ;;\n");
    if (print_free_values(out, t, "")) {
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
    static comp_table_t table;
    memset(&table, 0, sizeof table);
    help_each_command(read_command, &table);
    if (table.error != NULL) {
        cli_error("--completion: %s for completion.c's tables", table.error);
        return 1;
    }
    if (bash) {
        print_bash(stdout, &table);
    } else {
        print_zsh(stdout, &table);
    }
    return 0;
}
