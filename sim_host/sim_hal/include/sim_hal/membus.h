/* An in-memory RS-485 segment with simulated time: any number of stations in one process.
 *
 * Model: a character takes 11 bit times at its sender's rate and reaches every other station
 * when its stop bit ends. A station whose UART is set to another rate receives it with a
 * framing error (that is all the baud search needs to see). Two transmissions that overlap in
 * time corrupt each other's overlapping characters, as on a real line. A station never hears its
 * own characters. Time advances only in membus_run_until(), jumping from event to event.
 *
 * Two paths give the same result. A station that can take a telegram whole (membus_whole_rx_t)
 * gets it as one event at the end of its last character, with the character times computed, as
 * long as nothing can tell the difference: one telegram on the line, every listener at its
 * rate, between telegrams and willing (asked at the end of the first character), and nothing else
 * happening until the last character ends. Anything else — another transmission (a collision),
 * a station polled or the caller's run ending inside the telegram, a listener that wants
 * characters (baud search, a receiver inside garbage, a damaged telegram) — splits it into
 * characters before that moment, which then go one by one as before. characters_only turns
 * the telegram path off (the reference the tests compare it with).
 *
 * A station that takes telegrams whole may also sleep through the ones that do not concern it
 * (membus_sleep): the bus then neither asks it nor hands it those telegrams, and brings it up to
 * date (its catch_up) before anything else reaches it — a telegram that concerns it, a
 * character, its poll — and when membus_run_until_ns returns. Which telegrams concern a
 * sleeper the caller's key function says, once per telegram (membus_set_key). */
#ifndef SIM_HAL_MEMBUS_H
#define SIM_HAL_MEMBUS_H

#include "sim_hal/sim_station.h"

#ifndef MEMBUS_MAX_STATIONS
#define MEMBUS_MAX_STATIONS 128u /* every address 0..126, and a probe */
#endif
#ifndef MEMBUS_MAX_INFLIGHT
#define MEMBUS_MAX_INFLIGHT 2048u
#endif

#ifndef MEMBUS_TELEGRAM_MAX
#define MEMBUS_TELEGRAM_MAX 256u /* longer transmissions go as characters */
#endif

typedef struct membus membus_t;

/* A telegram on its way as a whole: character k (1..len) ends at start_ns + k * char_ns.
 * memo: one octet that is 0 when the telegram goes on the line and stays with it until it is
 * delivered; what every listener would work out alike from the octets alone (their check
 * sum) the first one asked may keep there for the others. */
typedef struct membus_telegram {
    const uint8_t *data;
    size_t len;
    uint64_t start_ns;
    uint32_t char_ns;
    uint32_t baud;
    uint8_t *memo;
} membus_telegram_t;

/* The timestamp rx_char would have been given for character k (1..len). */
static inline hal_time_us_t membus_char_us(const membus_telegram_t *tg, size_t k)
{
    return (hal_time_us_t)((tg->start_ns + (uint64_t)tg->char_ns * k) / 1000u);
}

/* What a station needs to take telegrams whole. takes: asked when the first character ends;
 * true only if rx() at the last character's end leaves the station exactly as rx_char for each
 * character would. rx returns whether the station is to be polled now, as after the last
 * character of a telegram; false only if the telegram gave its poll nothing to do (it is for
 * another station and changes nothing the poll reads), so the deadline its last poll returned
 * stands. */
typedef struct membus_whole_rx {
    void *ctx;
    bool (*takes)(void *ctx, const membus_telegram_t *tg);
    bool (*rx)(void *ctx, const membus_telegram_t *tg);
    /* For a station that sleeps: the telegrams it slept through leave it as rx() would have,
     * given the last of them and the one before (NULL when it slept through one only; the one
     * before is then the last it took itself). NULL: the station never sleeps. */
    void (*catch_up)(void *ctx, const membus_telegram_t *last, const membus_telegram_t *before);
} membus_whole_rx_t;

/* What a telegram's key function answers besides a sleeper's own key. */
#define MEMBUS_KEY_NONE 0xFEu /* concerns no sleeper */
#define MEMBUS_KEY_ALL 0xFFu  /* wakes every sleeper */
typedef uint8_t (*membus_key_fn)(void *ctx, const membus_telegram_t *tg);

typedef struct membus_port {
    membus_t *bus;
    sim_station_t station;
    uint32_t baud;
    uint64_t deadline_ns;
    uint8_t index;
    /* Cut off the bus: transmits nothing, hears nothing (a pulled connector). Changed between
     * runs only (no station sleeps then). */
    bool silenced;
    membus_whole_rx_t whole; /* rx NULL: characters only */
    bool asleep;             /* see membus_sleep */
    uint8_t key;
    uint64_t slept_after;    /* the bus's whole_seq when it fell asleep */
} membus_port_t;

typedef struct membus_char {
    uint64_t t_end_ns;
    uint32_t baud;
    uint8_t byte;
    uint8_t sender;
    bool corrupt;
    bool last_of_frame;
} membus_char_t;

/* The telegram in flight as a whole (at most one). */
typedef struct membus_whole {
    bool active;
    bool asked; /* the listeners said yes at the end of the first character */
    uint8_t sender;
    uint32_t baud;
    uint32_t char_ns;
    uint64_t start_ns;
    uint16_t len;
    uint8_t memo;
    uint8_t key; /* the key function's answer, when asked */
    uint8_t data[MEMBUS_TELEGRAM_MAX];
} membus_whole_t;

struct membus {
    uint64_t now_ns;
    membus_port_t ports[MEMBUS_MAX_STATIONS];
    uint8_t num_ports;
    membus_char_t queue[MEMBUS_MAX_INFLIGHT]; /* sorted by t_end_ns */
    size_t queue_len;
    uint64_t line_busy_until_ns;
    uint8_t line_busy_sender;
    /* Two slots: a listener may answer from inside the delivery of the other. */
    membus_whole_t whole[2];
    uint8_t whole_slot;
    /* The last two telegrams delivered whole (whole_seq counts them), for the sleepers. */
    membus_whole_t past[2];
    uint64_t whole_seq;
    unsigned sleepers;
    membus_key_fn key;
    void *key_ctx;
    bool characters_only;
    sim_frame_tap_t tap;
    void *tap_ctx;
    uint64_t chars_delivered;
    uint64_t telegrams_whole; /* delivered as one event */
    uint64_t telegrams_split; /* started whole, went on as characters */
    uint64_t slept_through;   /* a telegram times a station that slept through it */
    uint64_t frames_sent;
    uint64_t collisions;
    uint64_t dropped_overflow;
};

void membus_init(membus_t *bus);
/* Returns the port (NULL when full). Give port's uart to the station before running. */
membus_port_t *membus_attach(membus_t *bus, const sim_station_t *station, hal_uart_t *uart_out);
/* The station's state changed outside its callbacks (a command from the user): poll it now. */
static inline void membus_wake(membus_port_t *port) { port->deadline_ns = port->bus->now_ns; }
void membus_set_tap(membus_t *bus, sim_frame_tap_t tap, void *ctx);
/* The port's station takes telegrams whole (see above). */
void membus_set_whole_rx(membus_port_t *port, const membus_whole_rx_t *whole);
/* Telegrams concern a sleeper when key answers its key or MEMBUS_KEY_ALL. Without a key
 * function every telegram concerns every sleeper. */
void membus_set_key(membus_t *bus, membus_key_fn key, void *ctx);
/* From inside the port's whole rx, which returned or will return false: the station sleeps
 * through the telegrams that follow until one concerns it (key), as long as the caller
 * guarantees that each of them would leave it just as rx with that answer does, and that its
 * catch_up reproduces them. */
void membus_sleep(membus_port_t *port, uint8_t key);
/* Brings a sleeping port's station up to date and wakes it (before touching it from outside). */
void membus_catch_up(membus_port_t *port);
/* Runs every station until simulated time t_ns (absolute, from bus start). */
void membus_run_until_ns(membus_t *bus, uint64_t t_ns);
static inline void membus_run_for_us(membus_t *bus, uint64_t us)
{
    membus_run_until_ns(bus, bus->now_ns + us * 1000u);
}
static inline hal_time_us_t membus_now_us(const membus_t *bus)
{
    return (hal_time_us_t)(bus->now_ns / 1000u);
}

#endif
