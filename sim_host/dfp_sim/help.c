/* The text of dfp-sim --help, dfp-sim help CMD and the man page. Texts are kept without their
 * indentation: the printers add it, so the same lines serve the terminal and roff. */
#include "help.h"

#include <ctype.h>
#include <string.h>

/* The shared options a command takes (help_note_t.bit). */
enum {
    NOTE_RATE = 1u << 0,
    NOTE_CAPTURE = 1u << 1,
    NOTE_HTTP = 1u << 2,
    NOTE_LOG = 1u << 3,
    NOTE_LCM = 1u << 4,
    NOTE_SEGMENT = 1u << 5,
    NOTE_BUS = 1u << 6,
};

typedef struct {
    const char *name;
    const char *synopsis; /* after the name; "\n" between lines */
    const char *text;     /* what it does; "\n" between lines */
    unsigned notes;       /* NOTE_* */
} help_cmd_t;

typedef struct {
    unsigned bit;
    const char *term; /* the option or word described */
    const char *sep;  /* between term and text on the terminal */
    const char *text;
} help_note_t;

typedef struct {
    const char *term;
    const char *text;
} help_item_t;

static const char program[] = "dfp-sim";
static const char summary[] = "the DFP21B PROFIBUS-DP card, simulated on Linux";

/* After "dfp-sim ". */
static const char *const forms[] = {
    "COMMAND [options]",
    "help [COMMAND]",
    "COMMAND --help|-h",
    "--version",
};

static const char intro[] =
    "The emulated SEW DFP21B PROFIBUS-DP option card, with an emulated MOVIDRIVE behind it, on\n"
    "a tty or PTY, on a virtual segment over LCM, or with a DP master on a simulated bus; and\n"
    "the tools around it: a class-1 master, parameter services, captures, replay and record.\n"
    "dfp-sim help COMMAND or dfp-sim COMMAND --help shows one command.";

static const help_cmd_t commands[] = {
    {"demo", "[--capture FILE] [--lcm URL] [--http [ADDR:]PORT] [LOG OPTIONS]",
     "the card and a DP master on a simulated bus: start-up, cyclic data, watchdog,\n"
     "a wrong configuration; needs no hardware and ends by itself. With --http it runs\n"
     "at wall-clock speed and then keeps going, panel and API up, until Ctrl-C",
     NOTE_CAPTURE | NOTE_HTTP | NOTE_LOG | NOTE_LCM},
    {"slave",
     "--port DEV|--pty LINK|--bus lcm:CHANNEL [--lcm-url URL] [--key FILE]\n"
     "[--address N|N-M,...] [--baud RATE|auto] [--capture FILE] [--duration S]\n"
     "[--inverter sim|none|can:IFACE[:ADDR]] [--eeprom FILE|DIR] [--card-nvm FILE|DIR]\n"
     "[--echo-suppress] [--lcm URL] [--http [ADDR:]PORT] [LOG OPTIONS]",
     "the emulated card on a tty (USB-RS485 adapter) or PTY until SIGINT/SIGTERM;\n"
     "--pty LINK makes a PTY pair itself (no socat) and LINK a symbolic link to its\n"
     "other end, the serial device a master opens (a PLC tool, pyprofibus, dfp-sim\n"
     "master); an old link there is replaced, anything else refused; removed at exit;\n"
     "--bus lcm:CHANNEL puts it on a virtual segment over LCM instead, shared with the\n"
     "stations of other processes or machines (--lcm-url, else $LCM_DEFAULT_URL, else\n"
     "LCM's default udpm://239.255.76.67:7667?ttl=0; --key: see SEGMENT);\n"
     "--address is the DIP-switch setting (default 4; above 125 the card stays off the bus);\n"
     "--inverter: the emulated MOVIDRIVE (default; --eeprom keeps its parameters in FILE),\n"
     "none (PI words echo PO words), or a MOVIDRIVE on SBus through SocketCAN;\n"
     "--card-nvm keeps the card's own data (I&M1..I&M4) in FILE;\n"
     "several addresses (4-9, 3,5,7) put a line of cards, each with its own drive, on\n"
     "the one port: --eeprom and --card-nvm then name directories (driveN.ee, cardN.nvm);\n"
     "a file is used by one process at a time (a lock on FILE.lock)",
     NOTE_RATE | NOTE_CAPTURE | NOTE_HTTP | NOTE_LOG | NOTE_LCM | NOTE_SEGMENT},
    {"master",
     "--port DEV|--bus lcm:CHANNEL [--lcm-url URL] [--key FILE] --address N|N-M,...\n"
     "--config HEX "
     "[--prm HEX] [--cycles N] [--baud RATE] [--ident N] [--watchdog MS]\n"
     "[--master-address N] [--outputs HEX] [--timeout S] [BUS OPTIONS]\n"
     "[--capture FILE] [--verbose] [--reset-fault] [--echo-suppress] [--http [ADDR:]PORT]\n"
     "[LOG OPTIONS]",
     "the built-in class-1 master against one slave or several (up to 32, e.g. 3-34 or\n"
     "3,5,7-9, all with the same configuration); exit 0 once each ran N cycles (default\n"
     "100; 0: run until SIGINT, exit 0) in data exchange. --verbose logs the inputs,\n"
     "decoded, whenever they change. --prm is the user parameter part (Set_Prm from octet 7);\n"
     "default for ident 0x6003: 00 00 00 06 81 00 00 01 01. Like a PLC going to STOP, it\n"
     "leaves (after --cycles, or on SIGINT/SIGTERM) with Global_Control Clear_Data and zero\n"
     "outputs for 3 cycles; --reset-fault acknowledges a drive fault at start (control\n"
     "word bit 6 set, then cleared; the drive needs P101 = FIELDBUS); --echo-suppress for\n"
     "an adapter that hears its own transmissions (the token ring would take its own\n"
     "telegram heard back for a second station with its address, and leave the bus)",
     NOTE_RATE | NOTE_CAPTURE | NOTE_HTTP | NOTE_LOG | NOTE_SEGMENT | NOTE_BUS},
    {"inverter",
     "--can IFACE [--sbus-address N] [--eeprom FILE] [--duration S] [--channel2]\n"
     "[--quiet]",
     "the emulated MOVIDRIVE on SBus (SocketCAN, e.g. vcan0) until SIGINT/SIGTERM; prints\n"
     "every parameter service and state change. --sbus-address is P813 (0..63, default 0);\n"
     "--eeprom keeps non-volatile parameters in FILE across runs",
     0u},
    {"param",
     "--port DEV|--bus lcm:CHANNEL [--lcm-url URL] [--key FILE] --address N\n"
     "[--via channel|movilink|profidrive|c2] [--baud RATE] [--master-address N]\n"
     "[--timeout S] [--json] [--capture FILE] [--verbose] [--echo-suppress] [BUS OPTIONS]\n"
     "read PARAM [PARAM ...] | write PARAM VALUE [--volatile] | im0",
     "one parameter service against the card on a tty, or as a master on an LCM segment\n"
     "(--bus, --lcm-url, --key as for slave). PARAM: an index (8461, 0x210D), a P-number\n"
     "(P100), a name or a unique part of one (\"setpoint source\"), or an IPOS variable\n"
     "(H12 = 11012). VALUE: a raw number (3, -5, 0x10), an enumeration text (FIELDBUS) or\n"
     "a value in the parameter's unit (300.5, \"300 rpm\"). Results name the parameter\n"
     "(P100 setpoint source = 3 (FIELDBUS)). channel (default for read and write) brings\n"
     "the slave up with Param + 3 PD and uses the cyclic 8-byte channel; movilink /\n"
     "profidrive bring it up with DP-V1 parameters and use class-1 data set 47 (request id\n"
     "0x40 / 0x01, write 0x02 non-volatile); c2 opens a class-2 connection (no start-up),\n"
     "id 0x40, aborts it. im0 reads I&M0 over DP-V1: class 1 via movilink (the default for\n"
     "im0) or profidrive, or class 2 via c2; --via channel im0 is refused (exit 2).\n"
     "--volatile: write to RAM only (movilink, channel). read with up to 19 indices: one\n"
     "data set 47 request (not channel), one result line each. --master-address: default\n"
     "2 (1 with c2): use one no other master on the bus has (the card takes two masters\n"
     "with one address for one). A slave owned by another class-1 master is refused by\n"
     "its diagnosis: the timeout names that master. Exit 0 when every result is positive,\n"
     "1 on a negative one or none within --timeout (default 10 s), 2 on a bad command\n"
     "line or an unknown PARAM; --json: one JSON object per result (p_number, name,\n"
     "value, text ...); --echo-suppress as for master",
     NOTE_RATE | NOTE_CAPTURE | NOTE_SEGMENT | NOTE_BUS},
    {"convert",
     "IN OUT [--format pcap|pcapng|text] [--linktype profibus|user0] [--ns]\n"
     "[--in-format pcap|pcapng|text|lcm] [--channel NAME] [--quiet]",
     "copies a capture into another format or link type (e.g. user0 for the Wireshark\n"
     "dissector in tools/wireshark/); the output format defaults to OUT's extension\n"
     "(.pcapng, .txt, else pcap); damaged records are copied and reported",
     0u},
    {"replay",
     "FILE [--address N] [--check] [--speed real|max] [--baud RATE]\n"
     "[--format pcap|pcapng|text|lcm] [--inverter sim|none] [--inverter-delay US]\n"
     "[--fixed-baud] [--timing auto|line|relaxed] [--verbose] [--lcm URL]\n"
     "[--channel NAME] [--http [ADDR:]PORT] [--max-mismatches N] [--ignore MASK]\n"
     "[--report json|junit FILE]",
     "a bus capture played against the emulated card at its recorded times (the card's\n"
     "own recorded answers are left out: it makes its own); --check compares every reply\n"
     "with the recorded one and reports the first difference in detail, every difference\n"
     "(up to --max-mismatches, default 10, 0: all) and counts per service (exit 0: all\n"
     "match, 1: a difference or a damaged file, 2: bad command line or unreadable file).\n"
     "--ignore PI2,PI3 or SERVICE:N-M (dx:4-7, diag:6; repeatable) leaves plant-dependent\n"
     "octets out; --report json|junit FILE (repeatable) writes the check for CI. The\n"
     "address comes from the capture unless given; the rate from --baud, else the\n"
     "capture, else the lowest its timing allows. A capture from a tty/PTY (answers later\n"
     "than a line allows) is recognised: 12 Mbit/s, the card at its rate, the inverter\n"
     "at once (--timing line to replay it as a line's). --lcm publishes the\n"
     "replay's telegrams, card state and parameter services with the capture's times\n"
     "(file://OUT.lcm?mode=w writes an LCM log at any speed). --channel: an LCM log's\n"
     "telegram channel to read ('*' all; default DFP_TELEGRAM when the log has it beside\n"
     "others, else all; also for convert). --http serves the control API read-only while\n"
     "the replay runs (use --speed real). docs/replay.md",
     NOTE_RATE | NOTE_HTTP | NOTE_LCM},
    {"record",
     "--capture FILE --cycles N [--baud RATE] [--address N] [--dpv1] [--faults]\n"
     "[--foreign] [--param-every N] [--inverter sim|none] [--capture-format ...]",
     "the built-in master and the card on the simulated bus for N Data_Exchange cycles,\n"
     "parameter-channel services every N cycles (default 10, 0: none), every telegram\n"
     "into FILE: --dpv1 adds data set 47 (class 1) and a class-2 connection, --faults a\n"
     "watchdog expiry and a wrong configuration, --foreign a second slave and master",
     NOTE_RATE | NOTE_CAPTURE},
    {"line",
     "--dir DIR [--ports N] [--baud RATE] [--timing] [--card ADDR]... [--quiet]\n"
     "[--master ADDR --master-slaves N|N-M,...] [BUS OPTIONS] [--capture FILE]",
     "a virtual RS-485 segment any program joins: N PTY ports (default 2, up to 16)\n"
     "with links DIR/port1..DIR/portN (an old link there is replaced, anything else\n"
     "refused; removed at exit), until SIGINT/SIGTERM. What one port writes every\n"
     "other port reads, the writer does not (half duplex); each character takes 11 bit\n"
     "times at --baud (default 19200); --timing paces delivery to the characters' ends\n"
     "and keeps the idle gaps. Two talkers at once come out garbled to the listeners,\n"
     "and each collision is counted and told on stderr. --card ADDR (repeatable): an\n"
     "emulated DFP21B with its MOVIDRIVE on the in-memory bus, joined to the line;\n"
     "--master ADDR: the built-in master there too, owning --master-slaves (each a\n"
     "DFP21B with Param + 3 PD), in the token ring with the line's other masters (BUS\n"
     "OPTIONS); --quiet: only the cards' and the master's warnings. A port nobody reads\n"
     "drops what it would get (counted). At the end: per port octets, writes, drops and\n"
     "collisions.\n"
     "sim_host/line/README.md",
     NOTE_RATE | NOTE_CAPTURE | NOTE_BUS},
    {"monitor",
     "--port DEV|--bus lcm:CHANNEL [--lcm-url URL] [--key FILE]|FILE [--baud RATE]\n"
     "[--timing] [--tsl BITS] [--ttr BITS] [--seconds S] [--view top|log|none] [--report json|junit FILE]...\n"
     "[--expect N|N-M,...] [--max-repeats N] [--max-missing N] [--gsd FILE]...\n"
     "[--pcapng FILE] [--http [ADDR:]PORT] [LOG OPTIONS]",
     "a bus monitor: a station that only listens, on a tty or PTY (a USB adapter, a\n"
     "port of dfp-sim line), an LCM segment, or a capture FILE (offline). It keeps the\n"
     "live list: every station heard, active (in the token ring) or passive; for a DP\n"
     "slave its master, ident, DP state (Wait_Prm, Wait_Cfg, Data_Exch), configuration,\n"
     "parameters and diagnosis; per station requests, FCB repeats, missing answers,\n"
     "RS/RR/UE, garbled telegrams, Data_Exchange cycle and token rotation times; and\n"
     "the events (a slave leaving data exchange, a new station, the ring, Stat_Diag, a\n"
     "retry storm, a lost token, a late answer). --view top: a full-screen view (the\n"
     "default on a terminal), log: one line per event (the default otherwise), none.\n"
     "--baud: the line's rate (default 1.5M); --timing: the times are the line's own\n"
     "(dfp-sim line --timing, a capture of the simulated bus), so station delays are\n"
     "judged (against the MaxTsdr at --baud of the --gsd FILE whose Ident_Number the\n"
     "slave has; up to 16 files); --tsl, --ttr: the slot and target rotation times in bit times (default:\n"
     "the DP profile's slot time, rotations not judged). --seconds: stop after S\n"
     "(else at SIGINT/SIGTERM or the FILE's end). At the end a summary; --report json\n"
     "the whole live list, --report junit one case per check: every DP slave in\n"
     "Data_Exch (and each --expect N heard), at most --max-repeats N repeats and\n"
     "--max-missing N missing answers per slave. Exit 1 when a check fails. --pcapng:\n"
     "every telegram and garbled run (commented \"garbled\") into FILE as it goes\n"
     "(flushed every second; link type PROFIBUS_DL, ns times). --http (a live source):\n"
     "the panel's bus page and GET /api/v1/bus show this monitor; the API takes no\n"
     "action. --quiet and --log-level filter the event lines. docs/monitor.md",
     NOTE_RATE | NOTE_SEGMENT | NOTE_HTTP | NOTE_LOG},
    {"check-cfg", "HEX", "would the card accept this Chk_Cfg configuration?", 0u},
    {"gsd", "FILE [--json] [--module NAME]...",
     "what a GSD file says: ident, lengths, the rates with their MaxTsdr, the modules\n"
     "with their config octets and I/O lengths, the user parameters a master sends by\n"
     "default with each ExtUserPrmData (type, default, allowed values), the DP-V1 keys,\n"
     "keywords ignored; then the consistency problems with their lines (a supported rate\n"
     "without MaxTsdr, a module beyond Max_Input_Len, a default outside its range, DP-V1\n"
     "keys without DPV1_Slave ...). --module NAME (repeatable, up to 32): the user\n"
     "parameters with these modules configured, in this order (their own parameter\n"
     "octets follow the global ones). --json: the same as one JSON object. Exit 0 when\n"
     "consistent, 1 with problems, 2 for a file that cannot be read or parsed (the error\n"
     "names its line). sim_host/gsd/README.md",
     0u},
    {"conformance",
     "--port DEV|--bus lcm:CHANNEL|--card [--lcm-url URL] [--key FILE] --address A\n"
     "--gsd FILE [--module NAME]\n"
     "[--baud RATE|all] [--only PREFIX] [--master-address N] [--report junit|html FILE]...\n"
     "[--echo-suppress] [--list]",
     "the conformance suite for DP slaves: a test master runs the cases (GSD, FDL, DP state\n"
     "machine, timing, DP-V1; --list names them) against the slave at address A that FILE\n"
     "describes, and gives each PASS, FAIL or NOT APPLICABLE with the clause it checks and\n"
     "the telegrams that decided it. The slave is on a tty or PTY (--port, no timing), an\n"
     "LCM segment (--bus), or --card: the DFP21B card in process on the in-memory bus,\n"
     "timed to the bit, at --baud RATE or at every rate the GSD claims (--baud all). The\n"
     "tester holds the line alone (no token): no other master may be on it. --module: the\n"
     "GSD module start-ups configure (default the first); --only: the cases whose id starts\n"
     "with PREFIX; --master-address: the tester's class-1 address (default 1; 2 and 3 play\n"
     "the class-2 and a second class-1 master). --report junit|html FILE (up to two): also\n"
     "as JUnit XML or a self-contained HTML report. Exit 0 when no case fails, 1 when one\n"
     "does. docs/conformance.md",
     NOTE_RATE | NOTE_SEGMENT},
};

static const help_note_t notes[] = {
    {NOTE_RATE, "RATE", ": ", "9600 19200 45450 93750 187500 500000 1.5M 3M 6M 12M (also 19.2k ...)."},
    {NOTE_CAPTURE, "--capture FILE", " ",
     "writes every telegram: pcap (default), pcapng (.pcapng) or text (.txt), or\n"
     "as --capture-format pcap|pcapng|text says; link type PROFIBUS_DL (257) unless\n"
     "--capture-linktype user0 (147, for Wireshark); --capture-ns: nanosecond timestamps.\n"
     "docs/captures.md describes the formats."},
    {NOTE_HTTP, "--http [ADDR:]PORT", " ",
     "serves the control API (JSON, docs/api.md) and the front panel at /;\n"
     "127.0.0.1 unless ADDR is given. A taken port is an error (exit 2). Every client\n"
     "needs a token: the URL to open with it is printed on stderr at start (control\n"
     "panel at http://127.0.0.1:PORT/?token=...). Off loopback without TLS a warning\n"
     "says the token crosses the network in clear text."},
    {NOTE_HTTP, "--http-token-file FILE", " ",
     "the operator's token is FILE's first line (16..256\n"
     "printable ASCII characters, no spaces); else $DFP_SIM_TOKEN; else a random one is\n"
     "made at start."},
    {NOTE_HTTP, "--http-viewer-token-file FILE", " ",
     "the same for a viewer, who reads and watches but\n"
     "may not act (else $DFP_SIM_VIEWER_TOKEN; else there is no viewer)."},
    {NOTE_HTTP, "--http-no-auth", ": ",
     "no token: every client is operator. Refused (exit 2) unless ADDR is\n"
     "loopback (127.0.0.0/8, ::1); the Host, Origin and Content-Type checks stay."},
    {NOTE_HTTP, "--http-allow-host NAME", " ",
     "a Host name answered besides IP addresses and localhost\n"
     "(against DNS rebinding; repeatable, up to 8)."},
    {NOTE_HTTP, "--http-allow-origin ORIGIN", " ",
     "an Origin (scheme://host[:port]) whose pages may send\n"
     "actions besides the server's own (repeatable, up to 8)."},
    {NOTE_HTTP, "--http-cert FILE --http-key FILE", " ",
     "HTTPS with this PEM certificate and key (both or\n"
     "neither; exit 2 when unreadable or invalid). docs/api.md, \"Security\", says what is\n"
     "protected and what is not."},
    {NOTE_LOG, "LOG OPTIONS", ": ",
     "--quiet (warnings and errors only), --log-level error|warn|info|debug (debug\n"
     "adds every baud-search step), --timestamps bus|wall (ms since start, or clock time)."},
    {NOTE_BUS, "BUS OPTIONS", ": ",
     "the master is an FDL active station: it joins the token ring of the\n"
     "segment (or passes the token to itself alone) and sends only while it holds the\n"
     "token. Its bus parameters must match every other master's (a PLC's): --bus-profile\n"
     "dp|usb (dp: the DP profile's values for the rate; usb, the default on a tty, PTY or\n"
     "LCM segment: TSL 100 ms, max TSDR 10 ms, TTR 2 s, HSA 31, G 100, for adapters and\n"
     "hosts whose timing is milliseconds), then in bit times --tsl BITS (slot time),\n"
     "--min-tsdr BITS, --max-tsdr BITS, --tset BITS, --tqui BITS, --ttr BITS (target\n"
     "rotation time), --gap-factor G (1..100), --hsa N (highest station address, 1..126),\n"
     "--max-retry N (0..7). A set that breaks a rule (TSL above max TSDR ...) exits 2."},
    {NOTE_LCM, "--lcm URL", " ",
     "publishes the card's telegrams, state and parameter services to LCM (channels\n"
     "DFP_TELEGRAM, DFP_CARD_STATE, DFP_PARAM; sim_host/lcm_bridge/README.md)."},
    {NOTE_SEGMENT, "SEGMENT", ": ",
     "who can reach --bus lcm:CHANNEL: every process that can send to the LCM URL's\n"
     "group and port: this host (ttl=0), or with ttl>0 every machine of the LAN's\n"
     "multicast domain; a plain segment lets any of them drive the card, so a slave\n"
     "on one refuses a real drive (inverter can:IFACE). --key FILE (64 hex digits, mode 600; make one with\n"
     "head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \\n') signs every telegram and\n"
     "drops unsigned, wrongly signed and replayed ones (counted, logged); every station\n"
     "of the segment needs the same key, and the machines' clocks must agree within 2 s\n"
     "(NTP). Telegrams are signed, not encrypted: anyone on the group still reads them;\n"
     "whoever holds the key is trusted (docs/commissioning.md)."},
};

static const char exit_lead[] = "the same for every command";

/* What the commands return: cli.h's EXIT_USAGE is 2. */
static const help_item_t exit_codes[] = {
    {"0", "success; also a slave, inverter or master --cycles 0 stopped by SIGINT/SIGTERM, and\n"
          "help and --version"},
    {"1", "failure at run time: a negative or missing answer (param, master, demo), a refused\n"
          "configuration (check-cfg), an inconsistent GSD file (gsd), a difference or a\n"
          "damaged capture (replay --check, convert), a device or an output file that cannot\n"
          "be opened or written, results that could not be written to standard output"},
    {"2", "bad command line: unknown command or option, bad or missing value, unknown PARAM;\n"
          "an input file that cannot be read or is not a capture (convert, replay) or no\n"
          "GSD file (gsd), a --eeprom or --card-nvm path that is no regular file or in no\n"
          "writable directory, two files of the command line that are one (--capture and\n"
          "--eeprom, FILE and --report ...), a --pty path that is no symbolic link; an\n"
          "--eeprom or --card-nvm file in use by another process, a --http port that is\n"
          "taken, a bad token, a bad --http-cert or --http-key file, --http-no-auth off\n"
          "loopback"},
};

static const help_item_t environment[] = {
    {"LCM_DEFAULT_URL", "the LCM URL for --bus lcm:CHANNEL without --lcm-url and for --lcm ''\n"
                        "(unset: udpm://239.255.76.67:7667?ttl=0)"},
    {"DFP_SIM_TOKEN", "the control API's operator token when --http-token-file is not given"},
    {"DFP_SIM_VIEWER_TOKEN", "its viewer token when --http-viewer-token-file is not given"},
};

static const char see_also[] =
    "README.md, docs/commissioning.md, docs/api.md, docs/captures.md, docs/replay.md and\n"
    "sim_host/lcm_bridge/README.md in the source tree; wireshark(1) with "
    "tools/wireshark/profibus.lua";

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* ---- terminal ---- */

/* Every line of text: the first where the caller left the cursor, the others after indent
 * spaces. */
static void print_lines(FILE *out, const char *text, int indent)
{
    for (const char *p = text; *p != '\0';) {
        const char *nl = strchr(p, '\n');
        size_t len = nl != NULL ? (size_t)(nl - p) : strlen(p);
        if (p != text) {
            fprintf(out, "%*s", indent, "");
        }
        fprintf(out, "%.*s\n", (int)len, p);
        p += len + (nl != NULL ? 1u : 0u);
    }
}

/* prefix, the name and the synopsis; continuation lines line up after the name. */
static void print_synopsis(FILE *out, const char *prefix, const help_cmd_t *c)
{
    fprintf(out, "%s%s ", prefix, c->name);
    print_lines(out, c->synopsis, (int)(strlen(prefix) + strlen(c->name) + 1u));
}

static void print_notes(FILE *out, unsigned which)
{
    for (size_t i = 0; i < COUNT(notes); i++) {
        if ((notes[i].bit & which) != 0u) {
            fprintf(out, "%s%s", notes[i].term, notes[i].sep);
            print_lines(out, notes[i].text, 2);
        }
    }
}

/* lead: NULL, or a remark on the whole list. */
static void print_items(FILE *out, const char *title, const char *lead, const help_item_t *items,
                        size_t n)
{
    if (lead != NULL) {
        fprintf(out, "\n%s (%s):\n", title, lead);
    } else {
        fprintf(out, "\n%s:\n", title);
    }
    for (size_t i = 0; i < n; i++) {
        fprintf(out, "  %s  ", items[i].term);
        print_lines(out, items[i].text, (int)(strlen(items[i].term) + 4u));
    }
}

void help_print_all(FILE *out)
{
    for (size_t i = 0; i < COUNT(forms); i++) {
        fprintf(out, "%s%s %s\n", i == 0 ? "usage: " : "       ", program, forms[i]);
    }
    fputc('\n', out);
    print_lines(out, intro, 0);
    fputc('\n', out);
    unsigned all = 0;
    for (size_t i = 0; i < COUNT(commands); i++) {
        print_synopsis(out, "  ", &commands[i]);
        fputs("      ", out);
        print_lines(out, commands[i].text, 6);
        all |= commands[i].notes;
    }
    fputc('\n', out);
    print_notes(out, all);
    print_items(out, "EXIT STATUS", exit_lead, exit_codes, COUNT(exit_codes));
    print_items(out, "ENVIRONMENT", NULL, environment, COUNT(environment));
    fputs("\nSEE ALSO: ", out);
    print_lines(out, see_also, 2);
}

static const help_cmd_t *find_command(const char *name)
{
    for (size_t i = 0; i < COUNT(commands); i++) {
        if (strcmp(commands[i].name, name) == 0) {
            return &commands[i];
        }
    }
    return NULL;
}

bool help_print_command(FILE *out, const char *cmd)
{
    const help_cmd_t *c = find_command(cmd);
    if (c == NULL) {
        return false;
    }
    print_synopsis(out, "usage: dfp-sim ", c);
    fputs("\n  ", out);
    print_lines(out, c->text, 2);
    if (c->notes != 0u) {
        fputc('\n', out);
        print_notes(out, c->notes);
    }
    print_items(out, "EXIT STATUS", exit_lead, exit_codes, COUNT(exit_codes));
    return true;
}

const char *help_command_names(void)
{
    static char names[128];
    if (names[0] == '\0') {
        size_t n = 0;
        for (size_t i = 0; i < COUNT(commands) && n < sizeof names; i++) {
            n += (size_t)snprintf(names + n, sizeof names - n, "%s%s", i == 0 ? "" : ", ",
                                  commands[i].name);
        }
    }
    return names;
}

void help_each_command(help_command_fn *fn, void *ctx)
{
    for (size_t i = 0; i < COUNT(commands); i++) {
        const char *texts[2u + 2u * COUNT(notes)];
        size_t n = 0;
        texts[n++] = commands[i].synopsis;
        texts[n++] = commands[i].text;
        for (size_t k = 0; k < COUNT(notes); k++) {
            if ((notes[k].bit & commands[i].notes) != 0u) {
                texts[n++] = notes[k].term;
                texts[n++] = notes[k].text;
            }
        }
        fn(ctx, commands[i].name, texts, n);
    }
}

/* ---- man(7) ---- */

/* One line of text for roff: a backslash is \e, a minus \- (so options copy as typed), and a
 * leading . or ' (which roff would take for a request) gets the zero-width \&. */
static void man_text(FILE *out, const char *p, size_t len)
{
    if (len > 0u && (p[0] == '.' || p[0] == '\'')) {
        fputs("\\&", out);
    }
    for (size_t i = 0; i < len; i++) {
        if (p[i] == '\\') {
            fputs("\\e", out);
        } else if (p[i] == '-') {
            fputs("\\-", out);
        } else {
            fputc(p[i], out);
        }
    }
}

static void man_lines(FILE *out, const char *text, int indent)
{
    for (const char *p = text; *p != '\0';) {
        const char *nl = strchr(p, '\n');
        size_t len = nl != NULL ? (size_t)(nl - p) : strlen(p);
        if (p != text && indent > 0) {
            fprintf(out, "%*s", indent, "");
        }
        man_text(out, p, len);
        fputc('\n', out);
        p += len + (nl != NULL ? 1u : 0u);
    }
}

static void man_bold(FILE *out, const char *text)
{
    fputs("\\fB", out);
    man_text(out, text, strlen(text));
    fputs("\\fP", out);
}

static void man_items(FILE *out, const char *title, const char *lead, const help_item_t *items,
                      size_t n)
{
    if (strchr(title, ' ') != NULL) {
        fprintf(out, ".SH \"%s\"\n", title);
    } else {
        fprintf(out, ".SH %s\n", title);
    }
    if (lead != NULL) {
        fputc(toupper((unsigned char)lead[0]), out);
        man_text(out, lead + 1, strlen(lead + 1));
        fputs(".\n", out);
    }
    for (size_t i = 0; i < n; i++) {
        fputs(".TP\n", out);
        man_bold(out, items[i].term);
        fputc('\n', out);
        man_lines(out, items[i].text, 0);
    }
}

static void man_commands(FILE *out)
{
    fputs(".SH COMMANDS\n", out);
    for (size_t i = 0; i < COUNT(commands); i++) {
        const help_cmd_t *c = &commands[i];
        fputs(".SS ", out);
        man_text(out, c->name, strlen(c->name));
        fputs("\n.nf\n", out);
        man_bold(out, program);
        fputc(' ', out);
        man_bold(out, c->name);
        fputc(' ', out);
        man_lines(out, c->synopsis, (int)(strlen(program) + strlen(c->name) + 2u));
        fputs(".fi\n.PP\n", out);
        man_lines(out, c->text, 0);
    }
    fputs(".SH \"COMMON OPTIONS\"\n", out);
    for (size_t i = 0; i < COUNT(notes); i++) {
        fputs(".TP\n", out);
        man_bold(out, notes[i].term);
        fputc('\n', out);
        man_lines(out, notes[i].text, 0);
    }
}

void help_print_man(FILE *out, const char *version)
{
    fputs(".TH DFP\\-SIM 1 \"\" \"", out);
    man_text(out, program, strlen(program));
    fputc(' ', out);
    man_text(out, version, strlen(version));
    /* Neither hyphenated nor justified: option names must stay whole to be typed as printed. */
    fputs("\" \"User Commands\"\n.nh\n.ad l\n.SH NAME\n", out);
    man_text(out, program, strlen(program));
    fputs(" \\- ", out);
    man_text(out, summary, strlen(summary));
    fputs("\n.SH SYNOPSIS\n.nf\n", out);
    for (size_t i = 0; i < COUNT(forms); i++) {
        man_bold(out, program);
        fputc(' ', out);
        man_lines(out, forms[i], 0);
    }
    fputs(".fi\n.SH DESCRIPTION\n", out);
    man_lines(out, intro, 0);
    man_commands(out);
    man_items(out, "EXIT STATUS", exit_lead, exit_codes, COUNT(exit_codes));
    man_items(out, "ENVIRONMENT", NULL, environment, COUNT(environment));
    fputs(".SH \"SEE ALSO\"\n", out);
    man_lines(out, see_also, 0);
}
