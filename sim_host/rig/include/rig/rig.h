/* A rig: one simulation assembled in one place — the medium (the in-memory bus in simulated
 * time, a tty/PTY or an LCM segment in wall-clock time), the cards with their drives, an
 * optional DP master, and the taps that watch it (capture, log, LCM telemetry, the HTTP
 * control API).
 *
 * Every program that runs cards or a master builds a rig, so a new tap attaches here and every
 * command gets it the same way. Taps see everything that happens: telegrams on the medium, DP
 * events and LEDs of each card, the parameter services each drive answered, what the drive does
 * (enable, faults, ramps), and the master's events. The rig also carries out what a user does to
 * the hardware: pull a card's bus cable, power-cycle a card, set its DIP switches, set a drive's
 * digital inputs or raise a drive fault.
 *
 * Structs are caller-owned and large (a membus with its event queue, room for a card at every
 * address a DP slave can have, 11 MB): keep a rig in static storage. One thread runs it. */
#ifndef RIG_RIG_H
#define RIG_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lcm_bridge/lcm_segment.h"
#include "sim_hal/membus.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

#ifndef RIG_MAX_CARDS
#define RIG_MAX_CARDS 126u /* addresses 0..125: a whole segment of cards */
#endif
#define RIG_MAX_TAPS 8u

typedef enum rig_medium {
    RIG_MEDIUM_MEMBUS = 0, /* in-memory bus, simulated time */
    RIG_MEDIUM_TTY,        /* a tty or PTY (--port), wall clock */
    RIG_MEDIUM_LCM,        /* a virtual segment over LCM (--bus lcm:CHANNEL), wall clock */
} rig_medium_t;

/* What a drive did, seen from outside (the emulation has no event hook of its own: the rig
 * compares its state after every poll). */
typedef enum rig_drive_event_type {
    RIG_DRIVE_ENABLED = 0,   /* output stage on */
    RIG_DRIVE_INHIBITED,     /* output stage off */
    RIG_DRIVE_FAULT,         /* value = fault number */
    RIG_DRIVE_FAULT_RESET,   /* value = the fault that was reset */
    RIG_DRIVE_RAMP,          /* the speed started changing towards setpoint_mrpm */
    RIG_DRIVE_SPEED,         /* a quarter of the way, or the setpoint reached (value = 1) */
    RIG_DRIVE_INPUT,         /* value = DI00 level */
} rig_drive_event_type_t;

typedef struct rig_drive_event {
    rig_drive_event_type_t type;
    uint32_t value;
    int32_t speed_mrpm;
    int32_t setpoint_mrpm;
} rig_drive_event_t;

/* Why an action came: the taps log it. */
typedef enum rig_action_type {
    RIG_ACTION_CABLE = 0, /* value = connected */
    RIG_ACTION_POWER_CYCLE,
    RIG_ACTION_DIP,
    RIG_ACTION_FAULT_INJECTED,
} rig_action_type_t;

typedef struct rig_tap {
    void *ctx;
    /* Every telegram on the medium (see sim_frame_tap_t). */
    sim_frame_tap_t frame;
    void (*card_event)(void *ctx, unsigned card, const dp_event_t *ev);
    void (*led)(void *ctx, unsigned card, hal_led_id_t led, hal_led_mode_t mode);
    /* A parameter service the drive answered, with the request as the card sent it. */
    void (*param)(void *ctx, unsigned card, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                  const uint8_t rsp[ML_TELEGRAM_LEN]);
    void (*drive)(void *ctx, unsigned card, const rig_drive_event_t *ev);
    void (*action)(void *ctx, unsigned card, rig_action_type_t type, uint32_t value);
    void (*master_event)(void *ctx, const dp_master_event_t *ev);
    /* The built-in master's token ring (fdl_active.h). */
    void (*ring_event)(void *ctx, const fdl_active_event_t *ev);
} rig_tap_t;

typedef struct rig rig_t;

typedef struct rig_card {
    rig_t *rig;
    unsigned index;
    card_station_t cs;
    card_options_t opt;     /* as given; event/led/param hooks point at the rig */
    hal_uart_t medium_uart; /* what the medium gave this card */
    membus_port_t *port;    /* on the in-memory bus, taking telegrams whole; else NULL */
    bool cable;             /* bus connector plugged in */
    uint8_t next_address;   /* DIP switches as set now: read at the next power-up */
    char nvm_note[320];     /* why the drive's EEPROM or the card's NVM was not used as is */
    char eeprom_path[256];  /* opt's paths point here: the caller's strings may not last */
    char card_nvm_path[256];
    /* Drive watch (rig_drive_event_t). */
    bool w_known;
    bool w_enabled;
    uint8_t w_fault;
    int32_t w_from_mrpm;
    int32_t w_target_mrpm;
    uint8_t w_quarter;
    bool w_ramping;
} rig_card_t;

typedef struct rig_cfg {
    rig_medium_t medium;
    /* RIG_MEDIUM_TTY: the device, or an open descriptor when use_fd (the master end of a PTY
     * pair has no path); RIG_MEDIUM_LCM: channel and LCM URL (NULL = default). */
    const char *device;
    bool use_fd;
    int fd;
    const char *lcm_channel;
    const char *lcm_url;
    int16_t lcm_station_address; /* the local station's address on the segment (-1: several) */
    const uint8_t *lcm_key;      /* a keyed segment's 32-octet key (NULL: plain segment) */
    uint32_t baud;               /* the medium's starting rate */
    bool echo_suppress;          /* tty adapters that hear themselves */
    /* Optional: wraps the medium's UART of each card (telemetry that must know which frames
     * are the card's own). */
    hal_uart_t (*wrap_card_uart)(void *ctx, hal_uart_t inner);
    /* Optional, in-memory bus: wraps each card's station on the bus (what the card hears and
     * when it is polled: a test that damages received characters). */
    sim_station_t (*wrap_card_station)(void *ctx, sim_station_t inner);
    void *wrap_ctx;
    /* Wall-clock media: a runner shared with another rig, so both ends of a PTY pair run in one
     * loop (NULL: the rig's own). The rig does not tap a shared runner's frames. */
    tty_runner_t *shared_runner;
    /* RIG_MEDIUM_MEMBUS: a card is spared the telegrams that cannot concern it (to another
     * address) by default; with this set every telegram goes through the card's own receive
     * path, so its own checks are what decides (the conformance suite). */
    bool every_telegram_to_cards;
    /* RIG_MEDIUM_MEMBUS: where simulated time starts (a clock past 2^31 us finds wrap bugs). */
    uint64_t start_ns;
} rig_cfg_t;

struct rig {
    rig_cfg_t cfg;
    membus_t bus;
    tty_port_t port;
    dfp_lcm_segment_t segment;
    tty_runner_t own_runner;
    tty_runner_t *runner; /* own_runner or cfg.shared_runner */
    bool open;
    rig_card_t cards[RIG_MAX_CARDS];
    unsigned num_cards;
    dp_master_t master;
    bool has_master;
    bool has_listener; /* a wall-clock medium's one station only listens (rig_attach_listener) */
    membus_port_t *master_port;
    hal_uart_t master_uart;
    rig_tap_t taps[RIG_MAX_TAPS];
    unsigned num_taps;
};

void rig_init(rig_t *r, const rig_cfg_t *cfg);
/* Taps first (they see the cards' first events): returns 0, or -1 when full. */
int rig_add_tap(rig_t *r, const rig_tap_t *tap);
/* Opens the medium (tty/LCM). Returns 0, or -1 with a reason in err. */
int rig_open(rig_t *r, char *err, size_t errlen);
void rig_close(rig_t *r);
/* A card with its drive (opt->inverter). Returns the card, or NULL when the rig is full; the
 * drive's EEPROM and card NVM problems are in card->nvm_note (not fatal). The rig owns the
 * event/led/param hooks: anything in opt for them is replaced by the taps. Call after
 * rig_open. */
rig_card_t *rig_add_card(rig_t *r, const card_options_t *opt, hal_time_us_t now);
/* The built-in master (cfg->uart is filled in by the rig). Returns it, or NULL when there is one
 * already. */
dp_master_t *rig_add_master(rig_t *r, const dp_master_cfg_t *cfg, hal_time_us_t now);

/* Any other station on the in-memory bus (a scripted second master, a test's probe), polled
 * after those attached before it. Returns its port, or NULL on a wall-clock medium or when the
 * bus is full. */
membus_port_t *rig_attach_station(rig_t *r, const sim_station_t *st, hal_uart_t *uart);

/* A station that only listens (the bus monitor) as a wall-clock medium's one station: it gets
 * every character with its arrival time and is polled at its deadlines; no card or master can
 * join after it, nor it after them. Returns 0, or -1 on the in-memory bus (rig_attach_station
 * is the way there), before rig_open, or when the medium has its station. */
int rig_attach_listener(rig_t *r, const sim_station_t *st);

/* A station that transmits as it likes (the conformance suite's test master): on the in-memory
 * bus another station (rig_attach_station), on a wall-clock medium its one station, as the
 * listener is. Returns 0 with the uart it transmits on, or -1 (as those two). */
int rig_attach_tester(rig_t *r, const sim_station_t *st, hal_uart_t *uart);

/* The card by bus address (the DIP address at its last power-up), NULL if none. */
rig_card_t *rig_card_by_address(rig_t *r, uint8_t address);

/* Hardware actions. */
void rig_card_set_cable(rig_card_t *c, bool connected);
void rig_card_power_cycle(rig_card_t *c, hal_time_us_t now);
void rig_card_set_dip(rig_card_t *c, uint8_t address);
void rig_card_set_input(rig_card_t *c, bool di00);
void rig_card_inject_fault(rig_card_t *c, uint8_t fault);
/* After a change from outside the rig's callbacks: poll every station soon. */
void rig_wake(rig_t *r);

/* Time: simulated bus time (membus) or the tty clock, in µs. */
hal_time_us_t rig_now_us(const rig_t *r);
/* Nanoseconds since the medium started (the timeline of logs and captures). */
uint64_t rig_elapsed_ns(const rig_t *r);

/* Runs the medium. membus: simulated time advances to t_us. tty/LCM: the wall clock runs until
 * t_us or *stop. Returns 0, or -1 with tty_runner_error() (a device failed). */
int rig_run_until(rig_t *r, hal_time_us_t t_us, volatile const int *stop);
const char *rig_error(const rig_t *r);

/* For the tty/LCM loop: call fd's readable when it has data (a control queue's wake-up). */
int rig_add_fd(rig_t *r, int fd, tty_fd_readable_fn readable, void *ctx);
int rig_add_timer(rig_t *r, tty_timer_fn poll, void *ctx);

#endif
