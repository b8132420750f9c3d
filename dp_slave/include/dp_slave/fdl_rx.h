/* Byte-by-byte telegram assembler for SD1/SD2/SD3/SD4/SC, shared by the slave and the host
 * master. It checks everything that can be checked without knowing who is listening: character
 * errors, start delimiter, LE = LEr and its range, the repeated SD2, FCS, ED, and gaps inside a
 * telegram. Whether a request had TSYN idle before it is recorded (idle_before_ns) and judged by
 * the FDL layer, because a response may follow a request after only min TSDR.
 *
 * Two timing models (the rule itself is fdl_gap.h, shared with the MCU's collector):
 *  - strict: character timestamps are exact (MCU, in-memory bus); any pause longer than
 *    FDL_RX_GAP_TOLERANCE_NS inside a telegram aborts it;
 *  - relaxed: timestamps come from an OS that delivers bytes in chunks (PTY, USB adapter);
 *    pauses up to relaxed_gap_us are tolerated inside a telegram. */
#ifndef DP_SLAVE_FDL_RX_H
#define DP_SLAVE_FDL_RX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_wire.h"
#include "dp_slave/dp_config.h"
#include "hal/hal_time.h"

/* A timestamp in whole microseconds can be off by almost 1 µs; 12 Mbit/s characters are 917 ns. */
#define FDL_RX_GAP_TOLERANCE_NS 1000u
#define FDL_RX_RELAXED_GAP_US_DEFAULT 20000u
#define FDL_RX_RELAXED_RESYNC_US_DEFAULT 1000u
/* After this much silence the previous character no longer matters: every pause fdl_rx judges
 * (TSYN at 9.6 kbit/s 3.4 ms, relaxed gap 20 ms) is far shorter. fdl_rx_poll() forgets it then,
 * so an idle line longer than half the 32-bit microsecond clock (36 min) is still "long". */
#define FDL_RX_FORGET_US 1000000u

typedef enum fdl_rx_error {
    FDL_RX_OK = 0,
    FDL_RX_ERR_CHAR,      /* parity, framing or overrun flag on a character */
    FDL_RX_ERR_SD,        /* a character that cannot start a telegram */
    FDL_RX_ERR_LE,        /* LE != LEr or outside 4..249 */
    FDL_RX_ERR_SD_REPEAT, /* fourth octet of SD2 is not 0x68 */
    FDL_RX_ERR_FCS,
    FDL_RX_ERR_ED,
    FDL_RX_ERR_GAP, /* idle inside a telegram */
    FDL_RX_ERR_TSYN, /* a request without 33 bit times idle before it (judged by the FDL layer) */
    FDL_RX_ERR_COUNT
} fdl_rx_error_t;

typedef enum fdl_rx_result { FDL_RX_NOTHING = 0, FDL_RX_FRAME, FDL_RX_ERROR } fdl_rx_result_t;

typedef struct fdl_rx {
#if FDL_RX_CHAR_INPUT
    uint8_t buf[FDL_FRAME_MAX];
#endif
    uint16_t len;      /* octets collected of the telegram in progress */
    uint16_t expected; /* total length once known, else 0 */
    bool collecting;
    bool synced; /* the line is known to be between telegrams */
    bool have_last;
    bool strict;
    uint32_t char_ns;
    /* A request after less idle than this broke TSYN (33 bits less the gap tolerance), worked
     * out once per rate so the reply path compares instead of dividing. */
    uint32_t tsyn_short_ns;
    uint32_t relaxed_gap_us;
    uint32_t relaxed_resync_us;
    hal_time_us_t last_char_t;
    uint32_t idle_before_pending_ns;
    /* Valid after FDL_RX_FRAME: the telegram, its length, when its last character ended, and
     * how long the line was idle before its first character (UINT32_MAX if unknown). */
    const uint8_t *frame; /* buf, or the buffer of the telegram fdl_rx_telegram() was given */
    uint16_t frame_len;
    hal_time_us_t frame_end_t;
    uint32_t idle_before_ns;
    fdl_rx_error_t last_error;
    uint32_t error_count[FDL_RX_ERR_COUNT];
} fdl_rx_t;

void fdl_rx_init(fdl_rx_t *rx, uint32_t baud, bool strict);
void fdl_rx_set_baud(fdl_rx_t *rx, uint32_t baud);
/* Discard any telegram in progress, e.g. after the station transmitted or changed rate. */
void fdl_rx_reset(fdl_rx_t *rx);
#if FDL_RX_CHAR_INPUT
fdl_rx_result_t fdl_rx_char(fdl_rx_t *rx, uint8_t byte, uint8_t flags, hal_time_us_t t);
#endif

/* A telegram whose characters a receiver collected itself (fdl_collect.h in an interrupt, DMA,
 * an ASIC): its length followed from SD and LE, gaps and character errors were judged as it
 * came in. What is left is checked here (LE/LEr, the repeated SD2, FCS, ED); the result is the
 * same as if its characters had gone through fdl_rx_char(), with frame pointing at buf, which
 * must stay unchanged until the frame has been served. */
typedef struct fdl_rx_telegram {
    const uint8_t *buf;
    uint16_t len;
    fdl_rx_error_t error; /* what the collector found (then buf is not looked at), else FDL_RX_OK */
    hal_time_us_t end_t;
    uint32_t idle_before_ns; /* UINT32_MAX: unknown (long) */
    /* The octet sum of DA..DU mod 256 when the receiver added it up as the characters came (an
     * ASIC checks the FCS that way); then the FCS is compared with it instead of being summed
     * on the reply path. */
    bool sum_known;
    uint8_t sum;
} fdl_rx_telegram_t;
fdl_rx_result_t fdl_rx_telegram(fdl_rx_t *rx, const fdl_rx_telegram_t *tg);
/* Call at least once per 35 minutes of silence, best at the deadline it returns: after
 * FDL_RX_FORGET_US without a character the next one counts as after an idle line of unknown
 * (long) length, as the first one after init does. */
hal_time_us_t fdl_rx_poll(fdl_rx_t *rx, hal_time_us_t now);

const char *fdl_rx_error_name(fdl_rx_error_t e);

#endif
