/* The mismatches of a replay check, one by one (replay_options_t.on_mismatch), and a list that
 * keeps the first N of them for the reports (dfp-sim replay --max-mismatches, --report).
 *
 * The list spools its entries to a temporary file (tmpfile(3), gone when the process ends), so
 * memory stays flat however many are kept; without one (no temporary directory) the reports say
 * the list could not be kept. */
#ifndef REPLAY_MISMATCH_H
#define REPLAY_MISMATCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "capture/record.h"
#include "replay/decode.h"

/* One request whose answer differed. Octet offsets count from the answer's first octet. */
typedef struct replay_listed {
    uint64_t number;   /* 1 for the capture's first mismatch */
    replay_service_t service;
    uint64_t t_ns;     /* bus time of the request */
    uint64_t record;   /* the request's record and its position in the file */
    uint64_t position;
    bool expected_present; /* the capture shows an answer: */
    uint64_t expected_record;
    uint64_t expected_position;
    bool actual_present;   /* the card answered */
    uint16_t request_len;
    uint16_t expected_len;
    uint16_t actual_len;
    uint16_t data_offset;  /* where the recorded answer's data unit begins; 0: it has none */
    uint16_t masked;       /* octets of the answer left out of the comparison (--ignore) */
    uint8_t mask[CAP_MAX_RECORD / 8u]; /* bit n: octet n not compared */
    uint8_t request[CAP_MAX_RECORD];
    uint8_t expected[CAP_MAX_RECORD];
    uint8_t actual[CAP_MAX_RECORD];
} replay_listed_t;

/* The offsets (ascending) at which both answers have an octet, the octets differ and the octet
 * is not masked; returns how many there are (at most max are written). */
size_t replay_listed_diffs(const replay_listed_t *m, uint16_t *out, size_t max);

#define REPLAY_LIST_DEFAULT 10u
#define REPLAY_LIST_ALL UINT64_MAX

typedef struct replay_list {
    uint64_t max;    /* entries kept: the first max mismatches (REPLAY_LIST_ALL: all) */
    uint64_t kept;
    FILE *spool;
    bool failed;     /* the temporary file could not be made or written: */
    char error[160];
} replay_list_t;

void replay_list_init(replay_list_t *l, uint64_t max);
/* Keeps m when fewer than max are kept. Fits replay_options_t.on_mismatch (ctx: the list). */
void replay_list_add(void *list, const replay_listed_t *m);
/* Reading back, in order: rewind, then next until it returns false. */
bool replay_list_rewind(replay_list_t *l);
bool replay_list_next(replay_list_t *l, replay_listed_t *out);
/* Closes the temporary file (its space is freed). */
void replay_list_close(replay_list_t *l);

#endif
