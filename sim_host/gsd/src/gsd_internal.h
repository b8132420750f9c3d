/* Shared between the reader's files: the parser's state (on the caller's stack, never global)
 * and one statement of a logical line cut into its parts. */
#ifndef GSD_INTERNAL_H
#define GSD_INTERNAL_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "gsd/gsd.h"

typedef enum gsd_state {
    GSD_ST_BEFORE = 0, /* before #Profibus_DP */
    GSD_ST_GLOBAL,
    GSD_ST_MODULE,
    GSD_ST_PRMTEXT,
    GSD_ST_EXTPRM,
    GSD_ST_AFTER, /* another #section began: the rest is not DP's */
} gsd_state_t;

typedef struct gsd_parser {
    gsd_t *g;
    const char *name; /* the file, NULL for a text */
    char *err;
    size_t n;
    bool failed;
    gsd_state_t st;
    uint32_t block_line;            /* the line that opened the current block */
    char buf[GSD_MAX_LINE + 1u];    /* the logical line being joined */
    size_t len;
    uint32_t first_line;            /* where it began */
    uint32_t last_line;             /* the last physical line fed */
    bool continuing;                /* the last line ended with '\' */
    char phys[GSD_MAX_LINE + 2u];   /* one physical line of a file */
} gsd_parser_t;

/* Keyword [ (arg) ] [ = value | rest ]: pointers into the parser's buffer. */
typedef struct gsd_stmt {
    char kw[48];
    const char *arg; /* NULL: no parentheses */
    size_t arg_len;
    bool eq;         /* an '=' followed the keyword */
    const char *val; /* after '=' or after the keyword, leading blanks skipped */
    uint32_t line;
} gsd_stmt_t;

/* Reports "NAME:LINE: what" (line 0: "NAME: what") once; always false. */
bool gsd_fail(gsd_parser_t *p, uint32_t line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* One logical line (trimmed, NUL-terminated, not empty): false after reporting. */
bool gsd_statement(gsd_parser_t *p, char *text, uint32_t line);
/* Whether the file ended inside a block, with the error. */
bool gsd_finish(gsd_parser_t *p);

/* Value readers: advance *s past what they read (and the blanks after it). */
void gsd_skip_blanks(const char **s);
bool gsd_read_int(const char **s, int64_t *v);
bool gsd_same(const char *a, const char *b); /* ASCII case-insensitive equality */
char gsd_lower(char c);                      /* ASCII only: no locale */

typedef enum gsd_outcome { GSD_NOT_MINE = 0, GSD_DONE, GSD_FAILED } gsd_outcome_t;

void gsd_note(gsd_parser_t *p, gsd_note_kind_t kind, const char *kw, uint32_t line,
              uint32_t first_line);
bool gsd_expect_end(gsd_parser_t *p, const gsd_stmt_t *st, const char *s);
/* A number in lo..hi at *s. */
bool gsd_read_number(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, int64_t lo,
                     int64_t hi, int64_t *v);
/* Keyword = number and nothing else. */
bool gsd_plain_number(gsd_parser_t *p, const gsd_stmt_t *st, int64_t lo, int64_t hi,
                      int64_t *v);
bool gsd_store_string(gsd_parser_t *p, uint32_t line, const char *s, size_t len,
                      uint32_t *off);
bool gsd_read_string(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, uint32_t *off);
/* Octets 0..255 separated by commas into dst: 1, 0 after reporting, -1 (not reported) when
 * there are more than cap. */
int gsd_read_octets(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, uint8_t *dst,
                    size_t cap, size_t *n);

/* gsd_blocks.c: Ext_User_Prm_Data_Const/Ref (module: GSD_GLOBAL or its index), the openers of
 * blocks, and the statements inside each kind of block. */
gsd_outcome_t gsd_prm_keyword(gsd_parser_t *p, const gsd_stmt_t *st, int module);
gsd_outcome_t gsd_block_opener(gsd_parser_t *p, const gsd_stmt_t *st);
bool gsd_module_statement(gsd_parser_t *p, const gsd_stmt_t *st);
bool gsd_prmtext_statement(gsd_parser_t *p, const gsd_stmt_t *st);
bool gsd_extprm_statement(gsd_parser_t *p, const gsd_stmt_t *st);

#endif
