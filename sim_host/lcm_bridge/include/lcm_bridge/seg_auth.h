/* Keyed LCM segments (dfp-sim --bus lcm:CHANNEL --key FILE): signing every telegram a station
 * sends and verifying every one it receives (sim_host/lcm_bridge/README.md, "Keyed segments").
 *
 * A signed telegram is a dfp_lcm signed_telegram_t: the encoded telegram_t, the sender's id, a
 * sequence number and a tag, HMAC-SHA-512-256 (libsodium's crypto_auth) with the segment's
 * 32-octet key over the channel name and everything before the tag. The sequence number is the
 * sender's CLOCK_REALTIME in microseconds, made strictly increasing; a receiver takes a telegram
 * whose sequence is within DFP_SEG_WINDOW_US of its own clock and above the last one it took
 * from that sender. So a telegram cannot be moved to another channel, altered, or played again
 * (not even to a receiver started after the recording: it is then too old), assuming the
 * stations' clocks agree within the window (NTP).
 *
 * No cryptography here: libsodium computes and compares the tags. All state is in the structs
 * the caller owns. */
#ifndef DFP_LCM_BRIDGE_SEG_AUTH_H
#define DFP_LCM_BRIDGE_SEG_AUTH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define DFP_SEG_KEY_BYTES 32u
/* How far a telegram's sequence (sender's clock) may be from the receiver's clock. */
#define DFP_SEG_WINDOW_US 2000000
/* Senders a receiver remembers; one is forgotten only when its last sequence is out of the
 * window (so nothing it sent before can be taken again). */
#define DFP_SEG_SENDERS 256u
/* signed_telegram_t without its telegram: fingerprint 8, version 1, sender 8, sequence 8,
 * length 2; then the tag. */
#define DFP_SEG_HEAD 27u
#define DFP_SEG_TAG 32u
/* Largest encoded telegram_t carried (a 512-octet frame and telegram_t's 39 fixed octets). */
#define DFP_SEG_TELEGRAM_MAX 551u
#define DFP_SEG_SIGNED_MAX (DFP_SEG_HEAD + DFP_SEG_TELEGRAM_MAX + DFP_SEG_TAG)

/* Why a received message was dropped. */
typedef enum dfp_seg_drop {
    DFP_SEG_DROP_UNSIGNED,     /* a plain telegram_t on a keyed segment */
    DFP_SEG_DROP_SIGNED,       /* a signed_telegram_t where this station has no key */
    DFP_SEG_DROP_BAD_TAG,      /* another key, another channel, or altered */
    DFP_SEG_DROP_STALE,        /* sequence out of the window of the receiver's clock */
    DFP_SEG_DROP_REPLAYED,     /* sequence not above the last taken from its sender */
    DFP_SEG_DROP_SENDERS_FULL, /* a new sender while every entry is in the window */
    DFP_SEG_DROP_MALFORMED,    /* neither type, or not well-formed */
    DFP_SEG_DROP_REASONS
} dfp_seg_drop_t;

/* "unsigned", "signed", "bad signature", "stale", "replayed", "senders full", "malformed". */
const char *dfp_seg_drop_name(dfp_seg_drop_t why);

typedef struct dfp_seg_sender {
    int64_t id;
    int64_t last_seq;
} dfp_seg_sender_t;

typedef struct dfp_seg_auth {
    uint8_t key[DFP_SEG_KEY_BYTES];
    int64_t last_sent_seq;
    dfp_seg_sender_t senders[DFP_SEG_SENDERS];
    unsigned num_senders;
} dfp_seg_auth_t;

/* Reads a key file: 64 hex digits (32 octets) on one line, nothing else but a final newline;
 * a regular file neither group- nor world-readable (as ssh wants a private key). Returns 0,
 * or -1 with a one-line reason in err (naming the file and how to make a good one). */
int dfp_seg_key_load(const char *path, uint8_t key[DFP_SEG_KEY_BYTES], char *err, size_t errlen);

/* 0, or -1 when libsodium cannot start (sodium_init). */
int dfp_seg_auth_init(dfp_seg_auth_t *a, const uint8_t key[DFP_SEG_KEY_BYTES]);
/* Wipes the key. */
void dfp_seg_auth_clear(dfp_seg_auth_t *a);

/* The next sequence number for a telegram sent at now_us (wall clock, µs): now_us, or one
 * above the last when the clock did not move on (or went back). */
int64_t dfp_seg_next_seq(dfp_seg_auth_t *a, int64_t now_us);
/* Builds the signed_telegram_t of an encoded telegram_t (tlen octets) into out. Returns its
 * length, or 0 when tlen is 0, above DFP_SEG_TELEGRAM_MAX, or out is too small. */
size_t dfp_seg_sign(const dfp_seg_auth_t *a, const char *channel, int64_t sender_id,
                    int64_t seq, const uint8_t *telegram, size_t tlen, uint8_t *out,
                    size_t outmax);
/* A received signed_telegram_t's fields, after dfp_seg_parse. */
typedef struct dfp_seg_msg {
    int64_t sender_id;
    int64_t seq;
    const uint8_t *telegram; /* inside the buffer */
    size_t tlen;
} dfp_seg_msg_t;
/* True when buf starts with signed_telegram_t's fingerprint. */
bool dfp_seg_is_signed(const uint8_t *buf, size_t len);
/* Checks the layout (version, length field = what the buffer holds). 0, or -1 (malformed). */
int dfp_seg_parse(const uint8_t *buf, size_t len, dfp_seg_msg_t *m);
/* Verifies a parsed message received at now_us (wall clock) on channel: the tag, the window,
 * the sender's last sequence, in that order (only a telegram with a good tag changes the
 * senders). Returns -1 when it is taken (the sender's last sequence is now its own), else the
 * dfp_seg_drop_t why not. */
int dfp_seg_verify(dfp_seg_auth_t *a, const char *channel, const uint8_t *buf, size_t len,
                   const dfp_seg_msg_t *m, int64_t now_us);

/* Dropped messages, counted per reason and logged without flooding the log: the first one at
 * once, later ones as one summary line at most every DFP_SEG_LOG_INTERVAL_US. */
#define DFP_SEG_LOG_INTERVAL_US 1000000
typedef void (*dfp_seg_log_fn)(void *ctx, const char *line);
typedef struct dfp_seg_drops {
    uint64_t total[DFP_SEG_DROP_REASONS];
    uint64_t pending[DFP_SEG_DROP_REASONS]; /* since the last line */
    int64_t last_line_us;
    bool logged;
} dfp_seg_drops_t;
/* Counts a drop at now_us (any monotonic µs) and writes a line when it is time. detail: what
 * was dropped, for the first line ("sender 0x1234, station 2"; may be ""). */
void dfp_seg_drops_add(dfp_seg_drops_t *d, dfp_seg_drop_t why, const char *channel,
                       const char *detail, int64_t now_us, dfp_seg_log_fn log, void *ctx);
/* Writes the summary of drops not yet logged when the interval has passed (from a timer). */
void dfp_seg_drops_flush(dfp_seg_drops_t *d, const char *channel, int64_t now_us,
                         dfp_seg_log_fn log, void *ctx);
/* "unsigned 3, signed 0, bad signature 1, stale 0, replayed 2, senders full 0, malformed 0"
 * of counts (total or pending; all: the zeros too, else "unsigned 3, bad signature 1, ...");
 * returns buf. */
const char *dfp_seg_drops_text(const uint64_t counts[DFP_SEG_DROP_REASONS], bool all,
                               char *buf, size_t n);

#endif
