/* dfp-sim line: a virtual RS-485 segment that any program joins through a PTY (DIR/port1 ..
 * DIR/portN), with emulated cards inside on the in-memory bus (--card), until SIGINT/SIGTERM.
 * The rules are the line library's (sim_host/line/README.md); this is the I/O around them: the
 * ports, the bus paced to the wall clock, the capture and the figures. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "bus_opts.h"
#include "cli.h"
#include "commands.h"
#include "pty_link.h"
#include "report.h"
#include "line/line.h"
#include "line/line_bridge.h"
#include "rig/rig.h"
#include "rig/rig_log.h"
#include "sim_hal/host_clock.h"

#define LINE_MAX_PORTS 16u
#define LINE_MAX_CARDS 16u
#define LINE_READ_MAX 4096u

typedef struct line_opts {
    const char *dir;
    uint32_t ports;
    uint32_t baud;
    bool timing;
    bool quiet;
    capture_opts_t capture;
    const char *card_text[LINE_MAX_CARDS];
    size_t n_cards;
    uint8_t cards[LINE_MAX_CARDS]; /* from card_text */
    uint32_t master;
    bool master_seen;
    const char *master_slaves;
    bus_opts_t bus;
    /* from the above */
    fdl_bus_params_t ring;
    uint8_t slave_addr[DP_MASTER_MAX_SLAVES];
    size_t num_slaves;
} line_opts_t;

#define LINE_OPT(field) offsetof(line_opts_t, field)

static const cli_opt_t line_options[] = {
    {CLI_OPT("--dir", "DIR", CLI_TEXT, LINE_OPT(dir))},
    {CLI_OPT("--ports", "N", CLI_U32, LINE_OPT(ports)), .min = 1, .max = LINE_MAX_PORTS},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, LINE_OPT(baud))},
    {CLI_OPT("--timing", NULL, CLI_FLAG, LINE_OPT(timing))},
    {CLI_OPT("--card", "ADDR", CLI_LIST, LINE_OPT(card_text)), .aux = LINE_OPT(n_cards),
     .max = LINE_MAX_CARDS},
    {CLI_OPT("--quiet", NULL, CLI_FLAG, LINE_OPT(quiet))},
    {CLI_OPT("--master", "ADDR", CLI_U32, LINE_OPT(master)), .min = 0, .max = 126,
     .seen = CLI_SEEN(line_opts_t, master_seen)},
    {CLI_OPT("--master-slaves", "N|N-M,...", CLI_TEXT, LINE_OPT(master_slaves))},
};

static const cli_group_t line_groups[] = {
    {line_options, CLI_COUNT(line_options), 0},
    {bus_options, CLI_COUNT(bus_options), LINE_OPT(bus)},
    {capture_options, CLI_COUNT(capture_options), LINE_OPT(capture)},
};

const cli_command_t cli_line = {.name = "line", .groups = line_groups,
                                .n_groups = CLI_COUNT(line_groups)};

typedef struct line_port {
    pty_link_t pty;
    int fd; /* the master side: what the line reads and writes */
    char path[600];
} line_port_t;

/* One run: static storage (the rig holds a bus with its event queue). */
typedef struct line_run {
    line_t line;
    line_port_t ports[LINE_MAX_PORTS];
    unsigned n_ports;
    uint64_t t0_ns; /* the line's time 0 on the monotonic clock; the bus's time is the same */
    bool cards; /* the in-memory bus is on the line: cards, the master, or both */
    rig_t rig;
    rig_log_t log;
    line_bridge_t bridge;
    cap_writer_t cap;
    bool capturing;
    bool cap_failed;
} line_run_t;

/* ---- the command line --------------------------------------------------------------------- */

static bool line_cards(line_opts_t *o)
{
    for (size_t i = 0; i < o->n_cards; i++) {
        uint32_t a = 0;
        if (!cli_u32("--card", o->card_text[i], 0, 125, &a)) {
            return false;
        }
        for (size_t j = 0; j < i; j++) {
            if (o->cards[j] == a) {
                cli_error("line: --card %u given twice", a);
                return false;
            }
        }
        o->cards[i] = (uint8_t)a;
    }
    return true;
}

/* --master ADDR with its slaves, and the bus parameters of its token ring (the usb profile by
 * default: the other stations of the line are programs on PTYs). */
static bool line_master(line_opts_t *o)
{
    if (!o->master_seen) {
        if (o->master_slaves != NULL || bus_opts_given(&o->bus)) {
            cli_error("line: --master-slaves and the bus options belong to --master ADDR (the "
                      "programs on the ports have their own)");
            return false;
        }
        return true;
    }
    for (size_t i = 0; i < o->n_cards; i++) {
        if (o->cards[i] == o->master) {
            cli_error("line: --master %u is also a --card", o->master);
            return false;
        }
    }
    if (o->master_slaves == NULL) {
        cli_error("line: --master ADDR needs --master-slaves N|N-M,... (the slaves it owns)");
        return false;
    }
    if (!cli_address_list("--master-slaves", o->master_slaves, o->slave_addr, DP_MASTER_MAX_SLAVES,
                          &o->num_slaves)) {
        return false;
    }
    for (size_t i = 0; i < o->num_slaves; i++) {
        if (o->slave_addr[i] == o->master) {
            cli_error("line: --master %u is also one of its slaves", o->master);
            return false;
        }
    }
    return bus_opts_apply(&o->bus, "line", o->baud, true, &o->ring) &&
           bus_opts_own_ok(&o->ring, "line", "--master", o->master);
}

/* The master inside the line, in the ring with every other master of the line: each slave a
 * DFP21B with Param + 3 PD, watchdog 1 s. 0, or 1 after reporting. */
static int bus_master(line_run_t *r, const line_opts_t *o)
{
    dp_master_cfg_t mc = {.address = (uint8_t)o->master, .baud = o->baud, .token_ring = true,
                          .bus = o->ring};
    dp_master_t *m = rig_add_master(&r->rig, &mc, rig_now_us(&r->rig));
    if (m == NULL) {
        cli_error("line: cannot add master %u", o->master);
        return 1;
    }
    dp_master_slave_cfg_t sc = {.cfg = {0xF3, 0xF2}, .cfg_len = 2};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 1000, dfp21b_user_prm_default,
                                              sizeof dfp21b_user_prm_default);
    for (size_t i = 0; i < o->num_slaves; i++) {
        sc.address = o->slave_addr[i];
        (void)dp_master_add_slave(m, &sc);
    }
    return 0;
}

/* DIR is a directory the line may make its links in, and no DIR/portK is anything but an old
 * link. */
static bool line_dir_usable(const line_opts_t *o)
{
    struct stat st;
    if (stat(o->dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cli_error("line: --dir %s: not a directory", o->dir);
        return false;
    }
    if (access(o->dir, W_OK | X_OK) != 0) {
        cli_error("line: --dir %s: cannot make links there (%s)", o->dir, strerror(errno));
        return false;
    }
    for (unsigned k = 1; k <= o->ports; k++) {
        char link[600];
        char why[700];
        (void)snprintf(link, sizeof link, "%s/port%u", o->dir, k);
        if (!pty_link_usable(link, why, sizeof why)) {
            cli_error("line: %s: refused (only an old symbolic link is replaced)", why);
            return false;
        }
    }
    return true;
}

static int line_parse(line_opts_t *o, int argc, char **argv)
{
    *o = (line_opts_t){.ports = 2u, .baud = 19200u};
    bus_opts_defaults(&o->bus);
    if (cli_parse(&cli_line, argc, argv, o) != 0) {
        return EXIT_USAGE;
    }
    if (o->dir == NULL) {
        cli_error("line: --dir DIR is required (where the links port1..portN are made)");
        return EXIT_USAGE;
    }
    if (strlen(o->dir) > 500u) {
        cli_error("line: --dir: the path is longer than 500 octets");
        return EXIT_USAGE;
    }
    if (!line_cards(o) || !line_master(o) || !line_dir_usable(o)) {
        return EXIT_USAGE;
    }
    const cli_file_t files[] = {{"--capture", o->capture.path, false}};
    return cli_files_distinct("line", files, 1u) ? 0 : EXIT_USAGE;
}

/* ---- time and the bus ---------------------------------------------------------------------- */

static uint64_t line_now(const line_run_t *r)
{
    return host_clock_mono_ns() - r->t0_ns;
}

/* The bus runs up to the line's now, so what its stations sent until now is on the line before
 * a port's write of now is judged against it. */
static void bus_catch_up(line_run_t *r, uint64_t now_ns)
{
    if (r->cards && now_ns > r->rig.bus.now_ns) {
        membus_run_until_ns(&r->rig.bus, now_ns);
    }
}

/* When the bus has something to do next (a station's deadline, a character's end). */
static uint64_t bus_next_ns(const line_run_t *r)
{
    const membus_t *bus = &r->rig.bus;
    uint64_t next = UINT64_MAX;
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        if (bus->ports[i].deadline_ns < next) {
            next = bus->ports[i].deadline_ns;
        }
    }
    if (bus->queue_len > 0u && bus->queue[0].t_end_ns < next) {
        next = bus->queue[0].t_end_ns;
    }
    for (unsigned s = 0; s < 2u; s++) {
        const membus_whole_t *w = &bus->whole[s];
        if (w->active && w->start_ns + w->char_ns < next) {
            next = w->start_ns + w->char_ns;
        }
    }
    return next;
}

/* Every telegram a bus station sends, into the capture; the bridge's own transmissions are the
 * ports' writes, captured when they were read. */
static void bus_frame(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                      uint32_t baud)
{
    (void)local;
    (void)baud;
    line_run_t *r = ctx;
    if (r->bridge.injecting || !r->capturing) {
        return;
    }
    if (cap_writer_frame(&r->cap, t_ns, frame, len, CAP_DIR_TX) != 0) {
        r->cap_failed = true;
    }
}

/* The cards on the in-memory bus and the bridge that joins the bus to the line (the bus is the
 * line's station n_ports). 0, or 1 after reporting. */
static int bus_open(line_run_t *r, const line_opts_t *o)
{
    rig_cfg_t cfg = {.medium = RIG_MEDIUM_MEMBUS, .baud = o->baud};
    rig_init(&r->rig, &cfg);
    rig_log_init(&r->log, &r->rig, stdout);
    r->log.level = o->quiet ? RIG_LOG_WARN : RIG_LOG_INFO;
    r->log.time = RIG_LOG_TIME_BUS;
    r->log.name_cards = o->n_cards > 1u;
    rig_tap_t log_tap = rig_log_tap(&r->log);
    rig_tap_t cap_tap = {.ctx = r, .frame = bus_frame};
    char err[300];
    if (rig_add_tap(&r->rig, &log_tap) != 0 || rig_add_tap(&r->rig, &cap_tap) != 0 ||
        rig_open(&r->rig, err, sizeof err) != 0) {
        cli_error("line: the in-memory bus: cannot start");
        return 1;
    }
    for (size_t i = 0; i < o->n_cards; i++) {
        card_options_t co = {.address = o->cards[i], .fixed_baud = o->baud,
                             .strict_timing = false, .inverter = CARD_INVERTER_SIM};
        if (rig_add_card(&r->rig, &co, rig_now_us(&r->rig)) == NULL) {
            cli_error("line: cannot add card %u", o->cards[i]);
            return 1;
        }
    }
    if (o->master_seen && bus_master(r, o) != 0) {
        return 1;
    }
    line_bridge_init(&r->bridge, &r->line, r->n_ports);
    sim_station_t st = line_bridge_station(&r->bridge);
    hal_uart_t uart = {0};
    membus_port_t *port = rig_attach_station(&r->rig, &st, &uart);
    if (port == NULL || line_bridge_attached(&r->bridge, port, uart) != 0) {
        cli_error("line: cannot join the in-memory bus to the line");
        return 1;
    }
    r->cards = true;
    return 0;
}

/* ---- the ports ---------------------------------------------------------------------------- */

/* Takes what the line delivers to a port: as much as the PTY takes now, never waiting (a port
 * nobody reads drops the rest, and the line counts it). */
static size_t port_deliver(void *ctx, unsigned to, const uint8_t *data, size_t len)
{
    line_run_t *r = ctx;
    if (to >= r->n_ports) {
        return 0;
    }
    ssize_t n = write(r->ports[to].fd, data, len);
    return n > 0 ? (size_t)n : 0u;
}

static const char *station_name(const line_run_t *r, unsigned s, char *buf, size_t n)
{
    if (s >= r->n_ports) {
        return "bus";
    }
    (void)snprintf(buf, n, "port%u", s + 1u);
    return buf;
}

static void log_collisions(line_run_t *r)
{
    line_collision_t c;
    while (line_take_collision(&r->line, &c)) {
        char who[200] = "";
        size_t used = 0;
        for (unsigned s = 0; s < LINE_MAX_STATIONS && used < sizeof who - 16u; s++) {
            if ((c.stations & (1u << s)) != 0u) {
                char name[16];
                used += (size_t)snprintf(who + used, sizeof who - used, "%s%s",
                                         used > 0u ? ", " : "", station_name(r, s, name,
                                                                             sizeof name));
            }
        }
        fprintf(stderr, "line: collision at %.3f ms: %s talked at once, %u octets garbled\n",
                (double)c.t_ns / 1e6, who, c.octets);
    }
}

/* A port's write: onto the line, onto the bus at the time the line gave it, into the capture. */
static void port_read(line_run_t *r, unsigned k, uint64_t now_ns)
{
    uint8_t buf[LINE_READ_MAX];
    ssize_t n = read(r->ports[k].fd, buf, sizeof buf);
    if (n <= 0) {
        return; /* EAGAIN; no EOF or EIO while the line holds the slave side */
    }
    uint64_t start = now_ns;
    (void)line_write(&r->line, k, buf, (size_t)n, now_ns, &start);
    if (r->cards) {
        (void)line_bridge_inject(&r->bridge, buf, (size_t)n, start);
    }
    if (r->capturing && cap_writer_frame(&r->cap, start, buf, (size_t)n, CAP_DIR_RX) != 0) {
        r->cap_failed = true;
    }
}

/* The ports' PTY pairs and links. 0, or 1 after reporting (what was made is undone). */
static int ports_open(line_run_t *r, const line_opts_t *o)
{
    for (unsigned k = 0; k < o->ports; k++) {
        line_port_t *p = &r->ports[k];
        (void)snprintf(p->path, sizeof p->path, "%s/port%u", o->dir, k + 1u);
        char err[900];
        if (pty_link_open(&p->pty, p->path, err, sizeof err) != 0) {
            const char *why = strncmp(err, "slave: --pty: ", 14u) == 0 ? err + 14 : err;
            cli_error("line: %s: %s", p->path, why);
            return 1;
        }
        r->n_ports = k + 1u;
        p->fd = p->pty.master_fd;
        int fl = fcntl(p->fd, F_GETFL);
        if (fl < 0 || fcntl(p->fd, F_SETFL, fl | O_NONBLOCK) != 0) {
            cli_error("line: %s: cannot make the PTY non-blocking", p->path);
            return 1;
        }
    }
    return 0;
}

static void ports_close(line_run_t *r)
{
    for (unsigned k = 0; k < r->n_ports; k++) {
        pty_link_close(&r->ports[k].pty); /* closes fd as well: it is the pair's master side */
        r->ports[k].fd = -1;
    }
}

/* ---- the run ------------------------------------------------------------------------------- */

static int poll_timeout_ms(line_run_t *r, uint64_t now_ns)
{
    uint64_t next = line_next_due(&r->line, now_ns);
    if (r->cards) {
        uint64_t b = bus_next_ns(r);
        next = b < next ? b : next;
    }
    if (next <= now_ns) {
        return 0;
    }
    uint64_t ms = (next - now_ns + 999999u) / 1000000u;
    return ms > 200u ? 200 : (int)ms;
}

/* Until SIGINT/SIGTERM: 0, or 1 when a port failed. */
static int line_loop(line_run_t *r)
{
    struct pollfd pfd[LINE_MAX_PORTS];
    for (unsigned k = 0; k < r->n_ports; k++) {
        pfd[k] = (struct pollfd){.fd = r->ports[k].fd, .events = POLLIN};
    }
    while (!cli_stop) {
        uint64_t now = line_now(r);
        bus_catch_up(r, now);
        (void)line_deliver(&r->line, now, port_deliver, r);
        log_collisions(r);
        int n = poll(pfd, r->n_ports, poll_timeout_ms(r, now));
        if (n < 0 && errno != EINTR) {
            cli_error("line: poll: %s", strerror(errno));
            return 1;
        }
        now = line_now(r);
        bus_catch_up(r, now);
        for (unsigned k = 0; n > 0 && k < r->n_ports; k++) {
            if ((pfd[k].revents & (POLLERR | POLLNVAL)) != 0) {
                cli_error("line: %s: the PTY failed", r->ports[k].path);
                return 1;
            }
            if ((pfd[k].revents & POLLIN) != 0) {
                port_read(r, k, now);
            }
        }
    }
    return 0;
}

static void print_start(const line_run_t *r, const line_opts_t *o)
{
    for (unsigned k = 0; k < r->n_ports; k++) {
        printf("%s\n", r->ports[k].path);
    }
    printf("dfp-sim line: %u port%s at %s%s", r->n_ports, r->n_ports == 1u ? "" : "s",
           report_baud_text(o->baud), o->timing ? ", paced (--timing)" : "");
    for (size_t i = 0; i < o->n_cards; i++) {
        printf("%s%u", i == 0u ? "; cards on the in-memory bus: " : ", ", o->cards[i]);
    }
    if (o->master_seen) {
        printf("; master %u on the in-memory bus, slaves %s", o->master, o->master_slaves);
    }
    printf("; Ctrl-C ends it\n");
    (void)fflush(stdout);
}

static void print_figures(const line_run_t *r)
{
    unsigned n = r->n_ports + (r->cards ? 1u : 0u);
    printf("dfp-sim line: %llu collision%s\n", (unsigned long long)r->line.collisions,
           r->line.collisions == 1u ? "" : "s");
    for (unsigned s = 0; s < n; s++) {
        const line_station_stats_t *st = &r->line.st[s];
        char name[16];
        printf("  %-6s sent %llu octets in %llu writes, received %llu, dropped %llu, "
               "collisions %llu\n", station_name(r, s, name, sizeof name),
               (unsigned long long)st->tx_octets, (unsigned long long)st->tx_writes,
               (unsigned long long)(s < r->n_ports ? st->rx_octets : r->bridge.frames_to_bus),
               (unsigned long long)st->rx_dropped + (unsigned long long)st->tx_dropped,
               (unsigned long long)st->collisions);
    }
    if (r->cards) {
        printf("  (bus: the in-memory bus; it writes character by character and receives "
               "the ports' writes whole)\n");
    }
}

static int line_session(line_run_t *r, const line_opts_t *o)
{
    bool bus = o->n_cards > 0u || o->master_seen;
    line_init(&r->line, o->ports + (bus ? 1u : 0u), o->baud, o->timing);
    if (ports_open(r, o) != 0) {
        return 1;
    }
    if (o->capture.path != NULL) {
        capture_opts_t c = o->capture;
        c.w.baud = o->baud;
        struct timespec wall;
        (void)clock_gettime(CLOCK_REALTIME, &wall);
        char err[700];
        if (cap_writer_open(&r->cap, c.path, &c.w, (uint64_t)wall.tv_sec * 1000000000ull +
                            (uint64_t)wall.tv_nsec, err, sizeof err) != 0) {
            cli_error("line: %s", err);
            return 1;
        }
        r->capturing = true;
    }
    print_start(r, o);
    r->t0_ns = host_clock_mono_ns();
    if (bus && bus_open(r, o) != 0) {
        return 1;
    }
    int rc = line_loop(r);
    log_collisions(r);
    print_figures(r);
    return rc;
}

int cmd_line(int argc, char **argv)
{
    static line_opts_t o;
    static line_run_t r;
    int rc = line_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    cli_catch_stop_signals(); /* from now on a signal ends the run through ports_close */
    memset(&r, 0, sizeof r);
    rc = line_session(&r, &o);
    ports_close(&r);
    if (r.cards) {
        rig_close(&r.rig);
    }
    if (r.capturing) {
        r.capturing = false;
        if (cap_writer_close(&r.cap) != 0 || r.cap_failed) {
            cli_error("line: could not write the whole capture to %s", r.cap.path);
            rc = rc != 0 ? rc : 1;
        }
    }
    return rc;
}
