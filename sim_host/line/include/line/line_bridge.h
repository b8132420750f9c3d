/* The in-memory bus (sim_hal/membus.h) as one station of the line: whatever station the bus
 * holds -- the rig's cards, its master, a station attached with rig_attach_station -- joins the
 * line through it, all the same way.
 *
 * The bridge is a station on the bus. Each character a bus station sends reaches it when its
 * stop bit ends and goes onto the line as a write of that character (started one character
 * earlier), so the line sees the bus's telegrams with their own timing and checks them against
 * the ports like any write. What the line's other stations write, the bridge transmits on the
 * bus at the time the line gave it (line_bridge_inject), and the bus delivers it to its stations
 * character by character; the line therefore never delivers to the bridge itself (it is deaf
 * on the line). The bus's time and the line's time must be one timeline: the caller runs the bus
 * up to the line's now before it writes or injects. */
#ifndef LINE_LINE_BRIDGE_H
#define LINE_LINE_BRIDGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "line/line.h"
#include "sim_hal/membus.h"

typedef struct line_bridge {
    line_t *line;
    unsigned station; /* the bus's station number on the line */
    membus_port_t *port;
    hal_uart_t uart;
    /* True while the bridge transmits: a frame tap on the bus sees the bridge's own
     * transmissions and can tell them from the bus stations' by this. */
    bool injecting;
    uint64_t octets_from_bus;
    uint64_t frames_to_bus;
} line_bridge_t;

/* The bridge for station `station` of line (marked deaf there). */
void line_bridge_init(line_bridge_t *b, line_t *line, unsigned station);
/* The station to attach to the bus (membus_attach or rig_attach_station). */
sim_station_t line_bridge_station(line_bridge_t *b);
/* After attaching: the port and the UART the bus gave; sets the UART to the line's rate.
 * Returns 0, or -1 when the bus refused the rate. */
int line_bridge_attached(line_bridge_t *b, membus_port_t *port, hal_uart_t uart);
/* Transmits what another station wrote onto the bus, starting at start_ns on the line's
 * timeline (line_write's *start_ns). Returns 0, or -1 when the bus refused it. */
int line_bridge_inject(line_bridge_t *b, const uint8_t *data, size_t len, uint64_t start_ns);

#endif
