/* The log a person follows: what the cards, their drives and the master do, decoded with the
 * drive's parameter names and texts, one line per event. A rig tap; every line also goes to a
 * control bridge (the HTTP event stream) when one is attached.
 *
 * Levels: error, warn, info (the default: state changes, services, faults, ramps), debug
 * (every baud-search step, every Data_Exchange input of `master --verbose`). The baud search
 * is one line when it starts and one when it ends at info. */
#ifndef RIG_RIG_LOG_H
#define RIG_RIG_LOG_H

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>

#include "rig/rig.h"
#include "rig/rig_ctl.h"

typedef enum rig_log_time {
    RIG_LOG_TIME_BUS = 0, /* ms since the medium started (simulated time on the in-memory bus) */
    RIG_LOG_TIME_WALL,    /* local wall-clock time */
} rig_log_time_t;

typedef struct rig_log {
    rig_t *rig;
    FILE *out;
    rig_log_level_t level;
    rig_log_time_t time;
    rig_ctl_t *ctl;      /* NULL: print only */
    bool show_inputs;    /* master --verbose: decoded inputs whenever they change */
    bool slave_silent;   /* unanswered polls of a silent address are told once */
    bool name_cards;     /* a line of cards: every card's lines carry its address, also
                          * before the second card exists */
    uint32_t baud_steps[RIG_MAX_CARDS];
    uint8_t last_inputs[DP_MASTER_MAX_SLAVES][DP_MASTER_MAX_IO];
    uint16_t last_inputs_len[DP_MASTER_MAX_SLAVES];
} rig_log_t;

void rig_log_init(rig_log_t *l, rig_t *r, FILE *out);
rig_tap_t rig_log_tap(rig_log_t *l);
void rig_log(rig_log_t *l, rig_log_level_t level, const char *source, const char *kind,
             const char *fmt, ...) __attribute__((format(printf, 5, 6)));
void rig_vlog(rig_log_t *l, rig_log_level_t level, const char *source, const char *kind,
              const char *fmt, va_list ap);
/* Prints a line another thread published to the control bridge (the API's audit) on the
 * terminal, as rig_log would have at its time t_us, without publishing it again. */
void rig_log_print(rig_log_t *l, rig_log_level_t level, const char *source, uint64_t t_us,
                   const char *text);
/* "error", "warn", "info", "debug" → level; false for anything else. */
bool rig_log_level_parse(const char *text, rig_log_level_t *level);
const char *rig_log_level_name(rig_log_level_t level);

/* The log's text of a card's DP event and of a master event (not DP_MASTER_EV_INPUTS), with its
 * level and kind; false when the event is not told. baud_steps and slave_silent carry state
 * between calls (search steps; a silent address told once). Every printer uses these. */
bool rig_card_event_text(const dp_event_t *ev, const dfp21b_t *card, uint32_t *baud_steps, char *out,
                         size_t n, rig_log_level_t *level, const char **kind);
bool rig_master_event_text(const dp_master_event_t *ev, bool *slave_silent, char *out, size_t n,
                           rig_log_level_t *level, const char **kind);
/* "Station_Not_Ready Prm_Req | Master_Add 2, ident 0x6003" for a Slave_Diag answer: the
 * standard octets by their names (Ext_Diag_Overflow of octet 3 too), the rest in hex. */
void rig_diag_text(const uint8_t *d, size_t len, char *out, size_t max);
const char *rig_baud_text(uint32_t baud);
/* PO/PI words of a DFP21B image (after the parameter channel), decoded: control word 1, speed
 * setpoint; status word 1, speed, current. */
void rig_pi_text(const uint16_t *pi, unsigned n, char *out, size_t max);
void rig_po_text(const uint16_t *po, unsigned n, char *out, size_t max);

#endif
