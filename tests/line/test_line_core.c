/* The line's rules at given times (sim_host/line): half duplex, pacing, a write queued behind
 * its own, collisions (where the garbled characters land, who hears what, the report), the
 * garble rule for every pair of characters, drops, and the in-memory bus joined through the
 * bridge in both directions. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "line/line.h"
#include "line/line_bridge.h"
#include "sim_hal/membus.h"

static line_t line;

/* What each station was given, and how much a station takes (SIZE_MAX: all). */
typedef struct got {
    uint8_t data[LINE_MAX_STATIONS][256];
    size_t len[LINE_MAX_STATIONS];
    size_t takes[LINE_MAX_STATIONS];
} got_t;

static got_t got;

static size_t take(void *ctx, unsigned to, const uint8_t *data, size_t len)
{
    got_t *g = ctx;
    size_t n = len < g->takes[to] ? len : g->takes[to];
    memcpy(g->data[to] + g->len[to], data, n);
    g->len[to] += n;
    return n;
}

static void reset_got(void)
{
    memset(&got, 0, sizeof got);
    for (unsigned s = 0; s < LINE_MAX_STATIONS; s++) {
        got.takes[s] = SIZE_MAX;
    }
}

static void test_half_duplex(void)
{
    reset_got();
    line_init(&line, 3, 19200, false);
    const uint8_t abc[] = {0x10, 0x04, 0x02};
    uint64_t start = 0;
    CHECK(!line_write(&line, 0, abc, 3, 5000, &start));
    CHECK_EQ(start, 5000);
    CHECK_EQ(line_next_due(&line, 5000), 5000); /* no pacing: due at once */
    CHECK_EQ(line_deliver(&line, 5000, take, &got), 3);
    CHECK_EQ(got.len[0], 0);
    CHECK_BYTES(got.data[1], got.len[1], 0x10, 0x04, 0x02);
    CHECK_BYTES(got.data[2], got.len[2], 0x10, 0x04, 0x02);
    CHECK_EQ(line_next_due(&line, 6000), UINT64_MAX);
    CHECK_EQ(line.st[0].tx_octets, 3);
    CHECK_EQ(line.st[2].rx_octets, 3);
    /* The line stays busy for the three characters: a reply written at once starts after them
     * on the line's timeline, without a collision (the replier had heard it all). */
    CHECK_EQ(line.char_ns, 572917);
    CHECK(!line_write(&line, 1, abc, 1, 6000, &start));
    CHECK_EQ(start, 5000 + 3u * 572917u);
    CHECK_EQ(line.collisions, 0);
}

static void test_pacing(void)
{
    reset_got();
    line_init(&line, 2, 9600, true);
    const uint64_t c = line.char_ns;
    CHECK_EQ(c, 1145833);
    const uint8_t d[] = {1, 2, 3};
    CHECK(!line_write(&line, 0, d, 3, 1000, NULL));
    CHECK_EQ(line_next_due(&line, 1000), 1000 + c);
    CHECK_EQ(line_deliver(&line, 1000 + c - 1u, take, &got), 0);
    CHECK_EQ(line_deliver(&line, 1000 + c, take, &got), 1);
    CHECK_BYTES(got.data[1], got.len[1], 1);
    CHECK_EQ(line_deliver(&line, 1000 + 3u * c, take, &got), 2);
    CHECK_BYTES(got.data[1], got.len[1], 1, 2, 3);
    /* Idle kept: a write 10 characters later starts then. */
    uint64_t start = 0;
    CHECK(!line_write(&line, 0, d, 1, 1000 + 13u * c, &start));
    CHECK_EQ(start, 1000 + 13u * c);
}

static void test_own_queue(void)
{
    reset_got();
    line_init(&line, 2, 9600, true);
    const uint64_t c = line.char_ns;
    const uint8_t d[] = {1, 2, 3, 4};
    uint64_t start = 0;
    CHECK(!line_write(&line, 0, d, 2, 0, NULL));
    CHECK(!line_write(&line, 0, d + 2, 2, c / 2u, &start)); /* waits for its own */
    CHECK_EQ(start, 2u * c);
    CHECK_EQ(line.busy_until_ns, 4u * c);
    CHECK_EQ(line_deliver(&line, 4u * c, take, &got), 4);
    CHECK_BYTES(got.data[1], got.len[1], 1, 2, 3, 4);
    CHECK_EQ(line.collisions, 0);
}

static void test_collision(void)
{
    reset_got();
    line_init(&line, 3, 9600, true);
    const uint64_t c = line.char_ns;
    const uint8_t a[] = {0x68, 0x68, 0x68, 0x68};
    const uint8_t b[] = {0x10, 0x10};
    CHECK(!line_write(&line, 0, a, 4, 0, NULL));
    uint64_t start = 0;
    /* Half way through the second character: b lands on the second and third. */
    CHECK(line_write(&line, 1, b, 2, c + c / 2u, &start));
    CHECK_EQ(start, c);
    line_collision_t col;
    CHECK(line_take_collision(&line, &col));
    CHECK_EQ(col.t_ns, c);
    CHECK_EQ(col.stations, 0x3);
    CHECK_EQ(col.octets, 2);
    CHECK(!line_take_collision(&line, &col));
    CHECK_EQ(line.st[0].collisions, 1);
    CHECK_EQ(line.st[1].collisions, 1);
    CHECK_EQ(line.st[2].collisions, 0);
    CHECK_EQ(line_deliver(&line, 4u * c, take, &got), 4);
    CHECK_BYTES(got.data[2], got.len[2], 0x68, 0x00, 0x00, 0x68);
    CHECK_EQ(got.len[0], 0);                           /* it drove all four */
    CHECK_BYTES(got.data[1], got.len[1], 0x68, 0x68); /* before and after it talked */
    /* A longer collider: one overlapping character, the rest after it; the line goes on. */
    reset_got();
    CHECK(!line_write(&line, 0, a, 2, 10u * c, NULL));
    CHECK(line_write(&line, 1, a, 3, 11u * c + 1u, &start));
    CHECK_EQ(start, 11u * c);
    CHECK_EQ(line.busy_until_ns, 14u * c);
    CHECK_EQ(line_deliver(&line, 14u * c, take, &got), 4);
    CHECK_BYTES(got.data[2], got.len[2], 0x68, line_garble(0x68, 0x68), 0x68, 0x68);
    CHECK_BYTES(got.data[0], got.len[0], 0x68, 0x68);
    CHECK_EQ(line.collisions, 2);
    const uint8_t e[] = {0xE5};
    CHECK(!line_write(&line, 2, e, 1, 20u * c, NULL));
    CHECK_EQ(line_deliver(&line, 21u * c, take, &got), 1);
    CHECK_EQ(got.data[0][got.len[0] - 1u], 0xE5);
}

/* Without pacing, two writes read in one round (before either could be heard) collide. */
static void test_collision_unpaced(void)
{
    reset_got();
    line_init(&line, 3, 19200, false);
    const uint8_t a[] = {0x68, 0x68, 0x68};
    const uint8_t b[] = {0x10};
    CHECK(!line_write(&line, 0, a, 3, 1000, NULL));
    CHECK(line_write(&line, 1, b, 1, 1000, NULL));
    CHECK_EQ(line_deliver(&line, 1000, take, &got), 3);
    CHECK_BYTES(got.data[2], got.len[2], 0x00, 0x68, 0x68);
}

static void test_garble(void)
{
    unsigned bad = 0;
    for (unsigned a = 0; a < 256u; a++) {
        for (unsigned b = 0; b < 256u; b++) {
            uint8_t g = line_garble((uint8_t)a, (uint8_t)b);
            bad += g == a || g == b;
        }
    }
    CHECK_EQ(bad, 0);
    CHECK_EQ(line_garble(0x68, 0x10), 0x00);
    CHECK_EQ(line_garble(0x68, 0x6C), 0x97); /* 0x68 covers: complement */
    CHECK_EQ(line_garble(0x16, 0x16), 0xE9);
    CHECK_EQ(line_garble(0x00, 0xFF), 0x55);
}

static void test_drops(void)
{
    reset_got();
    line_init(&line, 3, 19200, false);
    got.takes[2] = 1; /* a reader that does not keep up */
    const uint8_t d[] = {1, 2, 3};
    CHECK(!line_write(&line, 0, d, 3, 0, NULL));
    CHECK_EQ(line_deliver(&line, 0, take, &got), 3);
    CHECK_EQ(line.st[2].rx_octets, 1);
    CHECK_EQ(line.st[2].rx_dropped, 2);
    CHECK_EQ(line.st[1].rx_octets, 3);
    static uint8_t big[LINE_QUEUE + 10u];
    CHECK(!line_write(&line, 1, big, sizeof big, 1000000000u, NULL));
    CHECK_EQ(line.st[1].tx_dropped, 10);
    CHECK_EQ(line.st[1].tx_octets, LINE_QUEUE);
}

/* ---- the bridge -------------------------------------------------------------------------- */

static membus_t bus;
static uint8_t probe_rx[64];
static size_t probe_len;

static void probe_rx_char(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    (void)ctx;
    (void)flags;
    (void)t;
    probe_rx[probe_len++] = byte;
}

static hal_time_us_t probe_poll(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    return now + 100000u;
}

static void test_bridge(void)
{
    static line_bridge_t br;
    reset_got();
    line_init(&line, 2, 19200, true); /* station 0 a port, station 1 the bus */
    membus_init(&bus);
    sim_station_t probe = {.rx_char = probe_rx_char, .poll = probe_poll};
    hal_uart_t probe_uart;
    membus_attach(&bus, &probe, &probe_uart);
    CHECK_EQ(probe_uart.ops->set_baud(probe_uart.ctx, 19200), 0);
    line_bridge_init(&br, &line, 1);
    CHECK_EQ(line.deaf, 0x2);
    sim_station_t st = line_bridge_station(&br);
    hal_uart_t uart;
    membus_port_t *port = membus_attach(&bus, &st, &uart);
    CHECK_EQ(line_bridge_attached(&br, port, uart), 0);
    const uint64_t c = line.char_ns;
    /* A bus station's telegram reaches the port with the bus's timing. */
    const uint8_t sc[] = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};
    CHECK_EQ(probe_uart.ops->transmit(probe_uart.ctx, sc, sizeof sc, 0), 0);
    membus_run_until_ns(&bus, 6u * c);
    CHECK_EQ(br.octets_from_bus, 6);
    CHECK_EQ(line_next_due(&line, 0), c);
    CHECK_EQ(line_deliver(&line, 6u * c, take, &got), 6);
    CHECK_BYTES(got.data[0], got.len[0], 0x10, 0x02, 0x05, 0x00, 0x07, 0x16);
    CHECK_EQ(got.len[1], 0);
    /* A port's write reaches the bus station; the bus never hears it back through the line. */
    const uint8_t req[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    uint64_t start = 0;
    membus_run_until_ns(&bus, 10u * c);
    CHECK(!line_write(&line, 0, req, sizeof req, 10u * c, &start));
    CHECK_EQ(line_bridge_inject(&br, req, sizeof req, start), 0);
    membus_run_until_ns(&bus, 17u * c);
    CHECK_BYTES(probe_rx, probe_len, 0x10, 0x05, 0x02, 0x49, 0x50, 0x16);
    CHECK_EQ(line_deliver(&line, 17u * c, take, &got), 6);
    CHECK_EQ(got.len[1], 0);
    CHECK_EQ(br.octets_from_bus, 6);
    CHECK_EQ(line.collisions, 0);
}

int main(void)
{
    RUN_TEST(test_half_duplex);
    RUN_TEST(test_pacing);
    RUN_TEST(test_own_queue);
    RUN_TEST(test_collision);
    RUN_TEST(test_collision_unpaced);
    RUN_TEST(test_garble);
    RUN_TEST(test_drops);
    RUN_TEST(test_bridge);
    return check_report();
}
