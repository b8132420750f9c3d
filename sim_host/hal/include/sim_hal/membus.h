/* An in-memory RS-485 segment with simulated time: any number of stations in one process.
 *
 * Model: a character takes 11 bit times at its sender's rate and reaches every other station
 * when its stop bit ends. A station whose UART is set to another rate receives it with a
 * framing error (that is all the baud search needs to see). Two transmissions that overlap in
 * time corrupt each other's overlapping characters, as on a real line. A station never hears its
 * own characters. Time advances only in membus_run_until(), jumping from event to event. */
#ifndef SIM_HAL_MEMBUS_H
#define SIM_HAL_MEMBUS_H

#include "sim_hal/sim_station.h"

#ifndef MEMBUS_MAX_STATIONS
#define MEMBUS_MAX_STATIONS 40u
#endif
#ifndef MEMBUS_MAX_INFLIGHT
#define MEMBUS_MAX_INFLIGHT 2048u
#endif

typedef struct membus membus_t;

typedef struct membus_port {
    membus_t *bus;
    sim_station_t station;
    uint32_t baud;
    uint64_t deadline_ns;
    uint8_t index;
    bool silenced; /* cut off the bus: transmits nothing, hears nothing (a pulled connector) */
} membus_port_t;

typedef struct membus_char {
    uint64_t t_end_ns;
    uint32_t baud;
    uint8_t byte;
    uint8_t sender;
    bool corrupt;
    bool last_of_frame;
} membus_char_t;

struct membus {
    uint64_t now_ns;
    membus_port_t ports[MEMBUS_MAX_STATIONS];
    uint8_t num_ports;
    membus_char_t queue[MEMBUS_MAX_INFLIGHT]; /* sorted by t_end_ns */
    size_t queue_len;
    uint64_t line_busy_until_ns;
    uint8_t line_busy_sender;
    sim_frame_tap_t tap;
    void *tap_ctx;
    uint64_t chars_delivered;
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
