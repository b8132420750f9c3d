/* The in-memory bus as a station of the line (line_bridge.h). */
#include "line/line_bridge.h"

/* A character of a bus station, at the end of its stop bit (the bus's now). A character the bus
 * garbled (two of its own stations at once, or another rate) goes on as the 0xFF it delivered:
 * the line cannot carry the framing error, and the bus has counted that collision. */
static void bridge_rx_char(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    (void)flags;
    (void)t; /* the bus's now_ns has the same instant in ns */
    line_bridge_t *b = ctx;
    uint64_t end = b->port->bus->now_ns;
    uint64_t start = end > b->line->char_ns ? end - b->line->char_ns : 0u;
    (void)line_write(b->line, b->station, &byte, 1u, start, NULL);
    b->octets_from_bus++;
}

/* The bridge has no timers of its own. */
static hal_time_us_t bridge_poll(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    return now + 1000000u;
}

void line_bridge_init(line_bridge_t *b, line_t *line, unsigned station)
{
    *b = (line_bridge_t){.line = line, .station = station};
    line->deaf |= 1u << station;
}

sim_station_t line_bridge_station(line_bridge_t *b)
{
    return (sim_station_t){.ctx = b, .rx_char = bridge_rx_char, .poll = bridge_poll};
}

int line_bridge_attached(line_bridge_t *b, membus_port_t *port, hal_uart_t uart)
{
    b->port = port;
    b->uart = uart;
    return uart.ops->set_baud(uart.ctx, b->line->baud) == 0 ? 0 : -1;
}

int line_bridge_inject(line_bridge_t *b, const uint8_t *data, size_t len, uint64_t start_ns)
{
    b->injecting = true;
    int rc = b->uart.ops->transmit(b->uart.ctx, data, len, (hal_time_us_t)(start_ns / 1000u));
    b->injecting = false;
    if (rc == 0) {
        b->frames_to_bus++;
    }
    return rc == 0 ? 0 : -1;
}
