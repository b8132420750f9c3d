/* Replaying a bus capture against the emulated DFP21B (docs/replay.md).
 *
 * The card (a rig card: sim_host/sim_stations card_station, with the emulated MOVIDRIVE or none)
 * sits on the rig's in-memory bus (membus, simulated time) next to an injector port. Records are
 * fed one at a time (replay_feed): every telegram of the capture goes onto the bus at its recorded
 * time, except the card's own recorded answers: the card produces its own. Time starts at the first
 * record, where the card powers up (automatic baud search unless fixed_card_baud). A record stamped
 * earlier than the one before goes on after it (re-anchoring when it is a clock step: the records
 * after it keep their spacing from it); an idle gap in which the card has settled is shortened
 * by whole baud-search cycles (docs/replay.md, "Timing model").
 *
 * With check on, every request addressed to the card (DA == address, not broadcast) is matched
 * with the record that follows it when that is the card's answer (SC, or a response with SA ==
 * address), else "no answer", and with what the card transmitted before the next injected
 * telegram (seen through the bus tap). Octets are compared exactly, except those an --ignore
 * mask leaves out (replay/mask.h); every mismatch goes to on_mismatch (replay/mismatch.h keeps
 * a list of them for the reports).
 *
 * Memory is fixed: a few telegrams of context, the first mismatch, counters, the first damaged
 * records. Nothing grows with the capture. */
#ifndef REPLAY_REPLAY_H
#define REPLAY_REPLAY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "capture/record.h"
#include "replay/decode.h"
#include "replay/mask.h"
#include "replay/mismatch.h"
#include "rig/rig.h"
#include "sim_hal/membus.h"
#include "sim_stations/stations.h"

#define REPLAY_DEFAULT_BAUD 1500000u
/* Context kept for the first mismatch: the telegrams before its request. */
#define REPLAY_CONTEXT 6u
/* Damaged records listed in the report with their positions (all are counted). */
#define REPLAY_DAMAGED_LISTED 20u
/* The emulated MOVIDRIVE's time per parameter service; the same as dfp-sim demo and record. */
#define REPLAY_INVERTER_DELAY_US_DEFAULT 3000u
/* Gaps before a record without a time (text captures), in bit times at the bus rate. */
#define REPLAY_SYNTH_GAP_ANSWER_BITS 11u   /* min TSDR before an answer */
#define REPLAY_SYNTH_GAP_REQUEST_BITS 66u  /* twice TSYN before a request or token */
/* The bus runs in slices of at most this much bus time; the stop flag is looked at between
 * them, so a long gap is never a long wait for SIGINT. */
#define REPLAY_SLICE_NS 1000000000ull
/* With a service hook, --speed real waits for the wall clock in steps of at most this much. */
#define REPLAY_SERVICE_NS 20000000ull
/* How long after the last record the card's one-shot timers may still run out (replay.c,
 * settle_ns): the longest baud control, twice the longest DP watchdog 255 x 255 x 10 ms. An
 * idle gap is only shortened after this much of it has been simulated. */
#define REPLAY_GAP_SETTLE_NS (2ull * 255u * 255u * 10u * 1000000ull)

typedef enum replay_speed {
    REPLAY_SPEED_MAX = 0, /* simulated time only */
    REPLAY_SPEED_REAL,    /* the wall clock follows the capture's time */
} replay_speed_t;

typedef enum replay_source {
    REPLAY_FROM_CAPTURE = 0, /* a record put on the bus */
    REPLAY_FROM_CARD,        /* what the emulated card transmitted */
} replay_source_t;

/* Every telegram on the replay bus, for --verbose and LCM publishing. */
typedef struct replay_telegram {
    replay_source_t source;
    uint64_t t_ns;     /* bus time from the first record: start of the first character */
    uint64_t record;   /* capture record index (0 for the card's telegrams) */
    uint64_t position; /* its position in the file */
    uint32_t baud;
    const uint8_t *data;
    size_t len;
    const char *problem; /* the record's damage ("" if none) */
} replay_telegram_t;

typedef struct replay_options {
    uint8_t address;        /* the card's DIP address */
    bool check;
    uint32_t baud;          /* for records without a rate; 0: REPLAY_DEFAULT_BAUD. Must be one
                               of hal_uart_bauds[] (replay_init refuses others) */
    bool baud_override;     /* baud applies to every record, also those that carry a rate */
    bool fixed_card_baud;   /* the card starts at the bus rate instead of searching */
    card_inverter_t inverter; /* CARD_INVERTER_SIM or CARD_INVERTER_NONE */
    uint32_t inverter_delay_us;
    replay_speed_t speed;
    /* Non-zero when the user asked to stop (SIGINT): the bus stops at the next slice (at most
     * REPLAY_SLICE_NS of bus time), --speed real stops waiting. Optional. */
    volatile const int *stop;
    /* Optional observers. */
    void (*on_telegram)(void *ctx, const replay_telegram_t *t);
    void (*on_card_event)(void *ctx, uint64_t t_ns, const dp_event_t *ev);
    void *ctx;
    /* Every parameter service the card ran with its inverter (card_options_t.param_observer). */
    void (*param_observer)(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                           const uint8_t rsp[ML_TELEGRAM_LEN]);
    void *param_observer_ctx;
    /* Called by the replay's loop between slices of bus time and, with REPLAY_SPEED_REAL, at
     * least every REPLAY_SERVICE_NS while it waits for the wall clock: the control API's turn
     * (rig_ctl_service). Optional. */
    void (*service)(void *ctx);
    void *service_ctx;
    /* Octets left out of the check (--ignore); NULL: every octet is compared. */
    const replay_mask_t *mask;
    /* Every mismatch as it is found (replay_list_add keeps them for the reports). Optional. */
    void (*on_mismatch)(void *ctx, const replay_listed_t *m);
    void *mismatch_ctx;
} replay_options_t;

typedef struct replay_counts {
    uint64_t requests;
    uint64_t matched;
    uint64_t differ;
    uint64_t capture_silent; /* the capture shows no answer */
    uint64_t card_silent;    /* the card gave none */
    uint64_t missing;        /* the capture shows an answer, the card gave none */
    uint64_t extra;          /* the card answered, the capture shows none */
    uint64_t masked_octets;  /* octets of compared answers left out (mask, with their FCS) */
} replay_counts_t;

/* A telegram kept for the report (copied: the record is gone by then). */
typedef struct replay_kept {
    replay_source_t source;
    uint64_t t_ns;
    uint64_t record;
    uint64_t position;
    size_t len;
    uint8_t data[CAP_MAX_RECORD];
} replay_kept_t;

typedef struct replay_mismatch {
    bool valid;
    replay_service_t service;
    replay_kept_t request;
    bool expected_present;
    replay_kept_t expected;
    char expected_problem[96]; /* the recorded answer was damaged */
    char request_problem[96];  /* the request record was damaged */
    bool actual_present;
    replay_kept_t actual;
    bool fcb_repeat;           /* same FCB as the master's previous request (FCV=1) */
    /* The card: its DP state when the request began, its rate when the request had ended. */
    dp_state_t card_state;
    dp_baud_state_t baud_state;
    uint32_t card_baud;
    bool set_prm_seen;         /* a Set_Prm to the card occurred earlier in the capture */
    replay_dx_layout_t layout;
    uint8_t mask[CAP_MAX_RECORD / 8u]; /* octets not compared (replay_mask_answer) */
    replay_kept_t before[REPLAY_CONTEXT];
    unsigned n_before;
} replay_mismatch_t;

typedef struct replay_damaged {
    uint64_t record;
    uint64_t position;
    char problem[96];
} replay_damaged_t;

typedef struct replay {
    replay_options_t opt;
    /* The in-memory bus with the card (cards[0]) and the injector's port: the same assembly as
     * every other simulation, so the control API (rig_ctl) can watch a replay. */
    rig_t rig;
    card_station_t *cs; /* the card under test: rig.cards[0].cs */
    membus_port_t *inj_port;
    hal_uart_t inj_uart;
    uint32_t inj_baud;
    bool started;
    bool finished;
    /* time: a timed record's bus time is anchor_bus_ns + (its time - anchor_capture_ns). The
     * anchor is the first timed record, moved to a record whose time goes back or that follows a
     * shortened gap. */
    bool have_anchor;
    uint64_t origin_ns;      /* capture time minus bus time at the first anchor (may wrap) */
    uint64_t anchor_capture_ns;
    uint64_t anchor_bus_ns;
    bool have_last_time;
    uint64_t last_time_ns;   /* recorded time of the last timed record put on the bus (the
                                latest, when one came out of order) */
    uint64_t last_spacing_ns; /* recorded time between the last two timed records put on the
                                 bus, their time going forward (0: none yet) */
    bool interrupted;        /* *opt.stop stopped the bus short of a record's time */
    uint64_t last_inject_ns; /* bus time the last injected telegram started */
    uint64_t last_end_ns;    /* ... and ended */
    uint64_t wall_start_ns;
    bool time_resolution_us; /* every timed record so far on a whole microsecond */
    /* the record before this one */
    bool prev_request_to_card;   /* a request to the card that asks for an answer */
    /* the request waiting for its answer window to close */
    bool pending;
    replay_service_t pend_service;
    replay_kept_t pend_request;
    char pend_request_problem[96];
    bool pend_fcb_repeat;
    bool pend_expected;
    replay_kept_t pend_expected_rec;
    char pend_expected_problem[96];
    bool pend_actual;
    replay_kept_t pend_actual_rec;
    dp_state_t pend_card_state;
    /* FCB of the last request from each master to the card (bit 0x20 of FC; 0xFF: none) */
    uint8_t last_fc[128];
    bool set_prm_seen;
    /* what is being injected right now (the tap sees it) */
    bool injecting;
    const cap_record_t *inj_rec;
    /* results */
    replay_counts_t svc[REPLAY_SVC_COUNT];
    uint64_t mismatches;
    uint64_t masked_octets;  /* all services */
    replay_listed_t listed;  /* the mismatch being handed to on_mismatch */
    replay_mismatch_t first;
    replay_kept_t ring[REPLAY_CONTEXT + 2u]; /* + the request and its answer */
    unsigned ring_next;
    unsigned ring_len;
    replay_damaged_t damaged[REPLAY_DAMAGED_LISTED];
    uint64_t damaged_count;
    /* statistics */
    uint64_t records;
    uint64_t octets;         /* octets of all records */
    uint64_t injected;
    uint64_t own_answers;    /* the card's recorded answers (not injected) */
    uint64_t stray_answers;  /* card answers in the capture that follow no request to it */
    uint64_t card_tx;
    uint64_t unsolicited;    /* card transmissions with no request waiting */
    uint64_t untimed;        /* records given synthetic times */
    uint64_t backwards;      /* records whose time went back: */
    uint64_t out_of_order;   /* ... by less than last_spacing_ns: right after the one before */
    uint64_t clock_steps;    /* ... by more: re-anchored */
    uint64_t max_back_ns;    /* ... the largest step back */
    uint64_t first_back_record;
    uint64_t first_back_position;
    uint64_t gaps_cut;       /* idle gaps shortened (the card had settled) */
    uint64_t cut_ns;         /* ... bus time left out in all */
    uint64_t first_cut_record; /* the record after the first shortened gap */
    uint64_t first_cut_position;
    uint64_t gaps_turning;   /* long idle gaps kept whole: the emulated drive was turning */
    uint64_t odd_rate_records; /* records carrying a rate outside hal_uart_bauds[]: replayed at
                                  opt.baud */
    uint32_t first_odd_rate;
    uint64_t rate_overridden;  /* records whose recorded rate baud_override replaced */
    uint64_t deferred;       /* injected later than recorded: the line was busy */
    uint64_t deferred_beyond_resolution;
    uint64_t max_defer_ns;
    uint64_t first_conflict_record;
    uint64_t first_conflict_position;
    uint32_t min_baud_seen;  /* rates taken from the records (0: none) */
    uint32_t max_baud_seen;
    uint64_t last_record_ns; /* bus time of the last record */
    uint64_t last_index;     /* index of the last record fed */
    /* The file ends right after a request to the card: its answer is not in the capture, so
     * the request is not compared (a recorder stopped mid-exchange). */
    bool tail_unchecked;
    replay_service_t tail_service;
    uint64_t tail_record;
    uint64_t tail_position;
} replay_t;

/* r is large (the bus, the card, the inverter): give it static or heap storage. Returns 0, or -1
 * with the reason in err (the inverter's storage could not be set up). */
int replay_init(replay_t *r, const replay_options_t *opt, char *err, size_t errlen);
/* One record, in file order. */
void replay_feed(replay_t *r, const cap_record_t *rec);
/* The same for a record of at least one octet that m is replay_frame_parse's reading of. */
void replay_feed_frame(replay_t *r, const cap_record_t *rec, const replay_frame_t *m);
/* After the last record: lets the card answer the last request and closes the check. */
void replay_finish(replay_t *r);

/* The bus rate used for a record: the options' with baud_override, else the record's own if it
 * is a PROFIBUS rate, else the options'. Always one of hal_uart_bauds[]. */
uint32_t replay_bus_baud(const replay_t *r, const cap_record_t *rec);
/* Is baud one of the ten PROFIBUS rates (hal_uart_bauds[])? */
bool replay_is_profibus_baud(uint32_t baud);
/* The capture's clock at a bus instant, for telemetry: the first timed record's time plus the
 * bus time since and the bus time left out of shortened gaps. It runs on steadily across a clock
 * step in the capture (never backwards). Without any timed record, the bus time itself. */
uint64_t replay_capture_ns(const replay_t *r, uint64_t bus_ns);
/* One full baud search of the card over the ten rates, in ns: the period of an idle card. */
uint64_t replay_search_cycle_ns(void);
static inline uint64_t replay_total_requests(const replay_t *r)
{
    uint64_t n = 0;
    for (unsigned i = 0; i < REPLAY_SVC_COUNT; i++) n += r->svc[i].requests;
    return n;
}

/* How positions are named in the report: "byte" (pcap, pcapng), "line" (text), "event" (LCM). */
typedef struct replay_report_info {
    const char *file;
    const char *format;        /* "pcap" ... */
    const char *position_unit; /* "byte", "line", "event" */
    const char *address_source; /* "given with --address", "from the capture: ..." */
    const char *baud_source;    /* why this rate */
    const char *file_error;     /* the reader's error, NULL if the file was read to its end */
    const char *source_note;    /* what the reader chose on its own (an LCM log's channel) */
    bool interrupted;
    /* What the first pass inferred and why (replay/infer.h); NULL: nothing to say. */
    const struct replay_inferred *inferred;
    /* The kept mismatches, listed below the table and in the report files; NULL: none. */
    replay_list_t *list;
} replay_report_info_t;

/* The report of docs/replay.md. Returns the exit status it stands for: 0 every reply matched
 * (and the file was read to its end), 1 otherwise. */
int replay_report(const replay_t *r, const replay_report_info_t *info, FILE *out);
/* The verdict in one word or two: with the check "MATCH", "DIFFERENT", "INCOMPLETE" or "NOTHING
 * CHECKED", without it "replayed" or "replay incomplete"; *status (may be NULL) the exit status
 * it stands for. */
const char *replay_verdict(const replay_t *r, const replay_report_info_t *info, int *status);
/* The check as a JSON object (docs/replay.md "Report files"). Returns -1 when out has an error. */
int replay_report_json(const replay_t *r, const replay_report_info_t *info, FILE *out);
/* The check as JUnit XML: one testsuite, one testcase per service with requests (a failure
 * listing its kept mismatches) and one for the capture as a whole. -1 when out has an error. */
int replay_report_junit(const replay_t *r, const replay_report_info_t *info, FILE *out);

/* ---- which station answers: the first pass over a file ----------------------------------- */

#define REPLAY_SCAN_MAX 128u

/* Two consecutive timed records: the rate at which the first fits into the gap between them. */
typedef struct replay_scan_pair {
    uint64_t need_baud;   /* 0: no such pair */
    uint64_t record;      /* the second record */
    uint64_t prev_record; /* the first */
    uint64_t gap_ns;
    uint32_t bits;        /* bit times that had to fit into the gap */
} replay_scan_pair_t;

/* With at least this many timed request/answer pairs, one pair alone needing a higher rate than
 * all the others is taken for a bad timestamp and left out (replay_scan_rate). */
#define REPLAY_SCAN_OUTLIER_MIN_ANSWERS 8u

typedef struct replay_scan_rate {
    uint32_t baud;               /* 0: nothing to go by */
    replay_scan_pair_t decided;  /* the pair that decided it */
    bool outlier;                /* a single pair needing more was left out: */
    replay_scan_pair_t ignored;
} replay_scan_rate_t;

/* How a station's answers are timed, for telling a line's capture from a tty's. */
typedef struct replay_scan_station {
    uint64_t pairs;      /* timed requests to it followed directly by its answer */
    uint64_t off_line[HAL_UART_NUM_BAUDS]; /* ... that no line at hal_uart_bauds[i] produces:
                                              the answer begins before the request could have
                                              ended, or later than the card's max TSDR after */
    uint64_t min_gap_ns; /* from a request's start to its answer's */
    uint64_t max_gap_ns;
    uint8_t first;       /* its first request: 0 none yet, 1 waiting, 2 answered, 3 not */
    uint64_t first_record;
} replay_scan_station_t;

/* The DFP21B's latest answer (its GSD's MaxTsdr: 63.8 us, never below 15 bit times), with a
 * microsecond of slack for rounded timestamps. */
#define REPLAY_CARD_MAX_TSDR_NS 63800u
#define REPLAY_CARD_MAX_TSDR_MIN_BITS 15u

typedef struct replay_scan {
    uint64_t answers[REPLAY_SCAN_MAX]; /* answers seen from each address (slaves only) */
    bool master[REPLAY_SCAN_MAX];      /* sent a request or a token: a master */
    bool prev_request;
    uint8_t prev_da;
    uint64_t records;
    /* The rate: recorded (pcapng, LCM) or what the timing needs (replay_scan_rate). */
    uint32_t recorded_baud;
    bool have_prev_time;
    uint64_t prev_t_ns;
    size_t prev_len;
    uint64_t prev_index;
    uint64_t timed_answers;   /* requests followed by their answer, both with times */
    uint64_t timed_pairs;     /* consecutive timed records whose time does not go back */
    uint64_t backward_pairs;  /* ... whose time does: they say nothing about the rate */
    replay_scan_pair_t need;  /* the pair of records needing the highest rate */
    replay_scan_pair_t need2; /* the pair needing the highest rate after it */
    replay_scan_station_t station[REPLAY_SCAN_MAX];
    /* A line's bounds on an answer's start after a request of bounds_len octets (0: none yet),
     * per rate: before early_below[i] - 1 us it is too early, after late_above[i] too late. */
    size_t bounds_len;
    uint64_t early_below[HAL_UART_NUM_BAUDS];
    uint64_t late_above[HAL_UART_NUM_BAUDS];
} replay_scan_t;

void replay_scan_init(replay_scan_t *s);
void replay_scan_feed(replay_scan_t *s, const cap_record_t *rec);
/* The same for a record of at least one octet that m is replay_frame_parse's reading of. */
void replay_scan_feed_frame(replay_scan_t *s, const cap_record_t *rec, const replay_frame_t *m);
/* Addresses (0..125) that answered and never acted as a master, ascending. Returns how many
 * (at most max are written). */
unsigned replay_scan_result(const replay_scan_t *s, uint8_t *out, unsigned max);
/* The lowest PROFIBUS rate at which no recorded telegram begins before the one before it ended
 * and no answer before min TSDR after its request (12 Mbit/s when even that does not fit); 0
 * when the file has no request followed by its answer with times. Pairs whose time goes back
 * are left out, and with REPLAY_SCAN_OUTLIER_MIN_ANSWERS answers also a single pair that alone
 * needs a higher rate than every other (why says which). why may be NULL. */
uint32_t replay_scan_rate(const replay_scan_t *s, replay_scan_rate_t *why);

/* How the capture's times were taken. On a line (LINE) the times are the line's: every answer
 * of the card begins within min TSDR .. max TSDR after its request ended. On a tty or PTY
 * (RELAXED: dfp-sim slave/master/param --port --capture) the operating system times the
 * telegrams: octets arrive in bursts, answers come when the process gets to them. */
typedef enum replay_timing {
    REPLAY_TIMING_LINE = 0,
    REPLAY_TIMING_RELAXED,
} replay_timing_t;

typedef struct replay_scan_timing {
    replay_timing_t mode;
    uint32_t baud;       /* the rate the answers were judged at */
    uint64_t pairs;      /* the station's timed answers */
    uint64_t off_line;   /* ... that no line at that rate produces */
    uint64_t min_gap_ns; /* from a request's start to its answer's */
    uint64_t max_gap_ns;
} replay_scan_timing_t;

/* RELAXED when more than half of the timed answers of station address are off the line at
 * baud (one of hal_uart_bauds[]); LINE otherwise, also without any timed answer. why may be
 * NULL. */
replay_timing_t replay_scan_timing(const replay_scan_t *s, uint8_t address, uint32_t baud,
                                   replay_scan_timing_t *why);
/* Did the capture's first request to address (one that asks for an answer) get its answer?
 * *record (may be NULL): that request's record. False also without any request to it. */
bool replay_scan_first_answered(const replay_scan_t *s, uint8_t address, uint64_t *record);

/* ---- files ------------------------------------------------------------------------------- */

/* Called every few thousand records: how far the reader got. */
typedef void (*replay_progress_t)(void *ctx, uint64_t records, uint64_t file_pos,
                                  uint64_t file_size);

typedef struct replay_file_status {
    cap_format_t format;    /* what the file turned out to be */
    uint32_t linktype;
    uint64_t records;
    bool read_error;        /* the file could not be read to its end: error says where */
    bool interrupted;       /* *stop became non-zero */
    char error[1024];
    char note[240];         /* the reader's choice when it was not told (cap_reader_t.lcm_note) */
} replay_file_status_t;

/* "byte" for pcap/pcapng, "line" for text, "event" for LCM logs. */
const char *replay_position_unit(cap_format_t f);

/* Which file, read how: lcm_channel as for cap_reader_open_channel (NULL: inferred). */
typedef struct replay_input {
    const char *path;
    cap_format_t format;
    const char *lcm_channel;
} replay_input_t;

/* Streams the file through replay_feed (then replay_finish). Returns -1 when it cannot be
 * opened (st->error says why), else 0; a read error after some records is in st. stop may be
 * NULL. */
int replay_run_file(replay_t *r, const replay_input_t *src, volatile const int *stop,
                    replay_progress_t progress, void *ctx, replay_file_status_t *st);
/* The same through replay_scan_feed. */
int replay_scan_file(replay_scan_t *s, const replay_input_t *src, volatile const int *stop,
                     replay_progress_t progress, void *ctx, replay_file_status_t *st);
/* The first `records` records (or fewer) through replay_scan_feed. */
int replay_scan_file_head(replay_scan_t *s, const replay_input_t *src, uint64_t records,
                          volatile const int *stop, replay_file_status_t *st);
/* One pass through both: every record to replay_scan_feed, then to replay_feed (then
 * replay_finish). The first pass and the replay in one reading of the file, for a replay set
 * up from a guess at what the first pass will find: the caller checks the guess against the
 * finished scan, and replays again when it was wrong (the replay depends on nothing but its
 * options and the records). */
int replay_scan_run_file(replay_scan_t *s, replay_t *r, const replay_input_t *src,
                         volatile const int *stop, replay_progress_t progress, void *ctx,
                         replay_file_status_t *st);

#endif
