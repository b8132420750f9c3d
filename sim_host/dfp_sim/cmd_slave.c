/* dfp-sim slave: the card (or a line of cards) on a real tty or a PTY, on a PTY pair of its own
 * (--pty LINK, pty_link.h), or on a virtual segment over LCM (--bus lcm:CHANNEL), in wall-clock
 * time. Timing on a PC is relaxed (see fdl_rx.h):
 * the OS delivers bytes in chunks. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "commands.h"
#include "pty_link.h"
#include "session.h"
#include "can/inverter_can.h"
#include "sim_hal/file_nvm.h"
#include "sim_hal/host_clock.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

typedef struct slave_opts {
    medium_opts_t med;
    const char *pty; /* --pty LINK */
    const char *lcm_url;
    capture_opts_t capture;
    instrument_opts_t io;
    const char *address_text;
    uint32_t baud;
    uint32_t duration_s;
    bool echo;
    const char *inverter;
    const char *eeprom;
    const char *card_nvm;
    /* from the above */
    uint8_t addresses[DP_MASTER_MAX_SLAVES];
    size_t num_cards;
    card_inverter_t kind;
} slave_opts_t;

#define SLAVE(field) offsetof(slave_opts_t, field)

static const cli_opt_t slave_options[] = {
    {CLI_OPT("--pty", "LINK", CLI_TEXT, SLAVE(pty))},
    {CLI_OPT("--address", "N|N-M,...", CLI_TEXT, SLAVE(address_text))},
    {CLI_OPT("--baud", "RATE|auto", CLI_BAUD_AUTO, SLAVE(baud))},
    {CLI_OPT("--duration", "S", CLI_U32, SLAVE(duration_s)), .min = 1, .max = 86400u * 365u},
    {CLI_OPT("--inverter", "sim|none|can:IFACE[:ADDR]", CLI_TEXT, SLAVE(inverter))},
    {CLI_OPT("--eeprom", "FILE|DIR", CLI_TEXT, SLAVE(eeprom))},
    {CLI_OPT("--card-nvm", "FILE|DIR", CLI_TEXT, SLAVE(card_nvm))},
    {CLI_OPT("--echo-suppress", NULL, CLI_FLAG, SLAVE(echo))},
    {CLI_OPT("--lcm", "URL", CLI_TEXT, SLAVE(lcm_url))},
};

static const cli_group_t slave_groups[] = {
    {medium_options, CLI_COUNT(medium_options), SLAVE(med)},
    {slave_options, CLI_COUNT(slave_options), 0},
    {capture_options, CLI_COUNT(capture_options), SLAVE(capture)},
    {instrument_options, CLI_COUNT(instrument_options), SLAVE(io)},
    {instrument_http_options, CLI_COUNT(instrument_http_options), SLAVE(io.web)},
};

const cli_command_t cli_slave = {.name = "slave", .groups = slave_groups,
                                 .n_groups = CLI_COUNT(slave_groups)};

/* One address (0..127, above 125 the card stays off the bus) or a line of cards. */
static bool slave_addresses(slave_opts_t *o)
{
    o->num_cards = 1;
    if (strpbrk(o->address_text, "-,") != NULL) {
        return cli_address_list("--address", o->address_text, o->addresses,
                                DP_MASTER_MAX_SLAVES, &o->num_cards);
    }
    uint32_t single = 0;
    if (!cli_u32("--address", o->address_text, 0, 127, &single)) {
        return false;
    }
    o->addresses[0] = (uint8_t)single;
    return true;
}

static bool slave_inverter_kind(slave_opts_t *o)
{
    if (strcmp(o->inverter, "sim") == 0) {
        o->kind = CARD_INVERTER_SIM;
    } else if (strcmp(o->inverter, "none") == 0) {
        o->kind = CARD_INVERTER_NONE;
    } else if (strncmp(o->inverter, "can:", 4) == 0) {
        o->kind = CARD_INVERTER_LINK;
        /* Checked with the command line (exit 2), not first when the interface is opened. */
        char ifname[32];
        uint8_t sbus = 0;
        char err[300];
        if (inverter_can_parse(o->inverter, ifname, sizeof ifname, &sbus, err, sizeof err) != 0) {
            cli_error("slave: %s", err);
            return false;
        }
    } else {
        cli_error("slave: --inverter '%s': use sim (emulated MOVIDRIVE), none (PI echoes PO) or "
                  "can:IFACE[:ADDR] (a MOVIDRIVE on SBus)", o->inverter);
        return false;
    }
    if (o->eeprom != NULL && o->kind != CARD_INVERTER_SIM) {
        cli_error("slave: --eeprom belongs to the emulated inverter (--inverter sim)");
        return false;
    }
    return true;
}

static bool is_directory(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* A line of cards: emulated drives, and directories for their files. */
static bool slave_line_of_cards(const slave_opts_t *o)
{
    if (o->kind == CARD_INVERTER_LINK) {
        cli_error("slave: a line of cards (--address %s) needs emulated drives, not SBus",
                  o->address_text);
        return false;
    }
    const char *dirs[2] = {o->eeprom, o->card_nvm};
    for (unsigned k = 0; k < 2u; k++) {
        if (dirs[k] != NULL && !is_directory(dirs[k])) {
            cli_error("slave: with several addresses, %s names a directory (one file per "
                      "card in it): '%s' is not one", k == 0u ? "--eeprom" : "--card-nvm",
                      dirs[k]);
            return false;
        }
    }
    return true;
}

/* Several cards (--address 4-9) keep their drives' EEPROMs and their own NVM in a directory. */
static const char *per_card_path(const char *dir, const char *stem, uint8_t address, char *buf,
                                 size_t n)
{
    if (dir == NULL) {
        return NULL;
    }
    (void)snprintf(buf, n, "%s/%s%u.%s", dir, stem, address,
                   strcmp(stem, "drive") == 0 ? "ee" : "nvm");
    return buf;
}

/* Every file the command line writes: --capture, an LCM log (--lcm file://...?mode=w), and the
 * EEPROM and NVM files --eeprom/--card-nvm stand for, one of each per card of a line. n says how
 * many of files[] are set; the EEPROM and NVM files come last, from files[2]. */
typedef struct slave_files {
    cli_file_t files[2u + 2u * DP_MASTER_MAX_SLAVES];
    size_t n;
    char paths[2u * DP_MASTER_MAX_SLAVES][512];
    char lcm_log[512];
} slave_files_t;

static void slave_file_list(const slave_opts_t *o, slave_files_t *l)
{
    l->files[0] = (cli_file_t){"--capture", o->capture.path, false};
    l->files[1] = (cli_file_t){"--lcm", cli_lcm_log_written(o->lcm_url, l->lcm_log,
                                                            sizeof l->lcm_log),
                               false};
    l->n = 2u;
    const char *given[2] = {o->eeprom, o->card_nvm};
    for (unsigned k = 0; k < 2u; k++) {
        for (size_t i = 0; given[k] != NULL && i < o->num_cards; i++) {
            char *buf = l->paths[l->n - 2u];
            l->files[l->n++] = (cli_file_t){
                k == 0u ? "--eeprom" : "--card-nvm",
                o->num_cards > 1u ? per_card_path(given[k], k == 0u ? "drive" : "card",
                                                  o->addresses[i], buf, sizeof l->paths[0])
                                  : given[k],
                false};
        }
    }
}

/* No two of the files may be one (the capture, opened first, would truncate the EEPROM before
 * it is read), and every --eeprom/--card-nvm file must be a regular file or not exist yet in a
 * directory that does: opening a FIFO would block before the card starts, and a write would
 * rename a file over a device. */
static bool slave_files_usable(const slave_opts_t *o)
{
    static slave_files_t l;
    slave_file_list(o, &l);
    if (!cli_files_distinct("slave", l.files, l.n)) {
        return false;
    }
    for (size_t i = 2u; i < l.n; i++) {
        char why[600];
        int rc = file_nvm_check_path(l.files[i].path, why, sizeof why);
        if (rc != 0) {
            cli_error("slave: %s %s: refused%s", l.files[i].option, why,
                      rc == FILE_NVM_NOT_FILE ? " (give a regular file, or a path where one "
                                                "can be created)" : "");
            return false;
        }
    }
    return true;
}

/* --pty makes its own port: no other medium beside it, and LINK no file of somebody else's. */
static bool slave_pty_check(const slave_opts_t *o)
{
    if (o->pty == NULL) {
        return true;
    }
    if (o->med.dev != NULL || o->med.bus != NULL) {
        cli_error("slave: --pty LINK makes the card's own PTY pair: it excludes --port and --bus");
        return false;
    }
    char why[600];
    if (!pty_link_usable(o->pty, why, sizeof why)) {
        cli_error("slave: --pty %s: refused (give a path that does not exist yet, or an old "
                  "link to replace)", why);
        return false;
    }
    return true;
}

/* The command line into o: 0, or EXIT_USAGE after reporting. */
static int slave_parse(slave_opts_t *o, int argc, char **argv)
{
    *o = (slave_opts_t){.address_text = "4", .inverter = "sim"};
    instrument_defaults(&o->io, RIG_LOG_TIME_BUS);
    if (cli_parse(&cli_slave, argc, argv, o) != 0) {
        return EXIT_USAGE;
    }
    if (o->med.dev == NULL && o->med.bus == NULL && o->pty == NULL) {
        cli_error("slave: --port DEV is required (a tty such as /dev/ttyUSB0, or a PTY), or --pty "
                  "LINK (a PTY pair of the card's own), or --bus lcm:CHANNEL");
        return EXIT_USAGE;
    }
    if (!medium_check(&o->med, "slave") ||
        !medium_check_real_drive(&o->med, "slave", o->inverter) || !slave_pty_check(o) ||
        !slave_addresses(o) ||
        !slave_inverter_kind(o) || (o->num_cards > 1u && !slave_line_of_cards(o)) ||
        !slave_files_usable(o)) {
        return EXIT_USAGE;
    }
    return 0;
}

/* A log line holds RIG_CTL_TEXT octets: a longer note (two damaged images, with the card's NVM)
 * goes on in further lines, cut at a "; " (file_nvm.h: no reason contains one) so no file name
 * or reason is split; the card's NVM starts a line of its own. */
static void log_nvm_note(rig_log_t *log, const char *src, const char *note)
{
    const size_t room = RIG_CTL_TEXT - 40u; /* the "non-volatile storage ..." prefix */
    bool continued = false;
    while (*note != '\0') {
        size_t n = strlen(note);
        bool next_continues = true;
        const char *card = strstr(note, "; card NVM: "); /* each file on a line of its own */
        if (card != NULL && card > note && (size_t)(card - note) <= room) {
            n = (size_t)(card - note);
            next_continues = false;
        } else if (n > room) {
            n = room;
            for (size_t i = room - 1u; i > 0u; i--) {
                if (note[i] == ';' && note[i + 1u] == ' ') {
                    n = i;
                    break;
                }
            }
        }
        rig_log(log, RIG_LOG_WARN, src, "nvm", "non-volatile storage%s: %.*s",
                continued ? " (continued)" : "", (int)n, note);
        continued = next_continues;
        note += n;
        while (*note == ';' || *note == ' ') {
            note++;
        }
    }
}

/* Another process took a file between the check of the command line and the card's open (the
 * check would have refused it): reported as that check does, and the run ends. */
static bool nvm_in_use(const card_station_t *cs)
{
    const file_nvm_t *f[2] = {&cs->nvm, &cs->card_nvm};
    for (unsigned k = 0; k < 2u; k++) {
        if (f[k]->loaded == FILE_NVM_IMAGE_IN_USE) {
            cli_error("slave: %s %s: in use by another process: refused",
                      k == 0u ? "--eeprom" : "--card-nvm", f[k]->path);
            return true;
        }
    }
    return false;
}

/* Every card of the line on the medium, each with its drive: 0, or 1 (EXIT_USAGE: a file in
 * use) after reporting. */
static int slave_add_cards(session_t *s, const slave_opts_t *o, ml_link_t external)
{
    bool line = o->num_cards > 1u;
    s->in.log.name_cards = line;
    for (size_t k = 0; k < o->num_cards; k++) {
        uint8_t a = o->addresses[k];
        char ee_buf[512];
        char nvm_buf[512];
        card_options_t co = {.address = a, .fixed_baud = o->baud, .strict_timing = false,
                             .inverter = o->kind, .external_link = external,
                             .eeprom_path = line ? per_card_path(o->eeprom, "drive", a, ee_buf,
                                                                 sizeof ee_buf)
                                                 : o->eeprom,
                             .card_nvm_path = line ? per_card_path(o->card_nvm, "card", a,
                                                                   nvm_buf, sizeof nvm_buf)
                                                   : o->card_nvm};
        rig_card_t *rc = rig_add_card(&s->rig, &co, tty_now_us());
        if (rc == NULL) {
            cli_error("slave: cannot add card %u", a);
            return 1;
        }
        if (nvm_in_use(&rc->cs)) {
            return EXIT_USAGE;
        }
        if (rc->cs.nvm_note[0] != '\0') { /* in full: rc->nvm_note may be cut */
            char src[16] = "card";
            if (line) {
                (void)snprintf(src, sizeof src, "card %u", a);
            }
            log_nvm_note(&s->in.log, src, rc->cs.nvm_note);
        }
        if (a > DFP21B_MAX_ADDRESS) {
            rig_log(&s->in.log, RIG_LOG_WARN, "card", "dp_state",
                    "address %u is above 125: the card stays off the bus", a);
        }
    }
    return 0;
}

static void print_start_line(const session_t *s, const slave_opts_t *o, const pty_link_t *pty)
{
    char name[700];
    const char *medium = name;
    if (o->pty != NULL) {
        (void)snprintf(name, sizeof name, "its own PTY %s (masters open %s)", pty->pts, o->pty);
    } else {
        medium = session_medium_name(s, &o->med, name, sizeof name);
    }
    printf("dfp-sim slave: DFP21B on %s, DIP address %s, %s%s%s; inverter: %s%s%s\n", medium,
           o->address_text,
           o->baud != 0u ? "fixed " : "automatic baud rate",
           o->baud != 0u ? report_baud_text(o->baud) : "",
           o->med.bus != NULL || s->rig.port.parity_ok ? "" : " (device has no parity: a PTY)",
           o->kind == CARD_INVERTER_SIM ? "emulated MOVIDRIVE" : o->inverter,
           o->eeprom != NULL ? ", EEPROM " : "", o->eeprom != NULL ? o->eeprom : "");
    (void)fflush(stdout);
}

/* Until SIGINT/SIGTERM or --duration: 0, or 1 when the medium failed. */
static int slave_run(session_t *s, const slave_opts_t *o)
{
    uint64_t end_ns = o->duration_s != 0u
                          ? host_clock_mono_ns() + (uint64_t)o->duration_s * 1000000000ull
                          : 0u;
    while (!cli_stop && (end_ns == 0u || host_clock_mono_ns() < end_ns)) {
        if (rig_run_until(&s->rig, tty_now_us() + 200000u, &cli_stop) < 0) {
            cli_error("%s", rig_error(&s->rig));
            return 1;
        }
    }
    return 0;
}

static void log_stop(session_t *s, const slave_opts_t *o)
{
    for (size_t k = 0; k < o->num_cards; k++) {
        rig_log(&s->in.log, RIG_LOG_INFO, o->num_cards > 1u ? "sim" : "card", "dp_state",
                "stopping (%s); card %u state %s", cli_stop ? "signal" : "end",
                s->rig.cards[k].cs.card.address,
                dp_state_name(dp_slave_state(&s->rig.cards[k].cs.card.dp)));
    }
}

/* The card's run on the medium of o (pty: its own PTY pair, already made, or NULL). */
static int slave_session(const slave_opts_t *o, const pty_link_t *pty)
{
    static session_t s;
    static inverter_can_t can_link;
    int rc;
    int16_t station = (int16_t)(o->num_cards == 1u ? o->addresses[0] : -1); /* -1: several */
    if (!session_open(&s, &o->med, station, o->baud != 0u ? o->baud : hal_uart_bauds[0],
                      &o->capture, &o->io, o->echo)) {
        return 1;
    }
    if (pty != NULL) { /* errors name the device, not "fd 3" */
        (void)snprintf(s.rig.port.name, sizeof s.rig.port.name, "%s", pty->pts);
    }
    card_station_t *first = &s.rig.cards[0].cs;
    s.rep.card = &first->card;
    if (o->lcm_url != NULL &&
        session_telemetry(&s, o->lcm_url, &first->card, o->addresses[0]) != 0) {
        return session_end(&s, 1);
    }
    ml_link_t external = {0};
    if (o->kind == CARD_INVERTER_LINK) {
        char err[256];
        if (inverter_can_open(&can_link, o->inverter, card_station_param_response,
                              card_station_process_inputs, first, s.rig.runner, err,
                              sizeof err) != 0) {
            cli_error("%s", err);
            return session_end(&s, 1);
        }
        external = inverter_can_link(&can_link);
    }
    print_start_line(&s, o, pty);
    rc = slave_add_cards(&s, o, external);
    if (rc == 0) {
        rc = instrument_start_http(&s.in, &s.rig, &o->io, "slave", false);
    }
    if (rc == 0) {
        rc = slave_run(&s, o);
        log_stop(&s, o);
    }
    if (o->kind == CARD_INVERTER_LINK) {
        inverter_can_close(&can_link);
    }
    return session_end(&s, rc);
}

int cmd_slave(int argc, char **argv)
{
    static slave_opts_t o;
    static pty_link_t pty;
    int rc = slave_parse(&o, argc, argv);
    if (rc != 0 || o.pty == NULL) {
        return rc != 0 ? rc : slave_session(&o, NULL);
    }
    cli_catch_stop_signals(); /* from now on a signal ends the run through pty_link_close */
    char err[800];
    if (pty_link_open(&pty, o.pty, err, sizeof err) != 0) {
        cli_error("%s", err);
        return 1;
    }
    o.med.use_fd = true;
    o.med.fd = pty.master_fd;
    pty_link_hand_over(&pty); /* session_open owns it now, on failure too */
    rc = slave_session(&o, &pty);
    pty_link_close(&pty);
    return rc;
}
