/* dfp-sim: the DFP21B PROFIBUS-DP card, simulated on Linux. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "dfp21b/dfp21b.h"
#include "dp_slave/dp_cfg.h"

static const char usage[] =
    "usage: dfp-sim COMMAND [options]\n"
    "\n"
    "  demo [--capture FILE] [--lcm URL] [--http [ADDR:]PORT] [LOG OPTIONS]\n"
    "      the card and a DP master on a simulated bus: start-up, cyclic data, watchdog,\n"
    "      a wrong configuration; needs no hardware and ends by itself. With --http it runs\n"
    "      at wall-clock speed and then keeps going, panel and API up, until Ctrl-C\n"
    "  slave --port DEV|--bus lcm:CHANNEL [--lcm-url URL] [--address N|N-M,...]\n"
    "        [--baud RATE|auto] [--capture FILE] [--duration S]\n"
    "        [--inverter sim|none|can:IFACE[:ADDR]] [--eeprom FILE|DIR] [--card-nvm FILE|DIR]\n"
    "        [--echo-suppress] [--lcm URL] [--http [ADDR:]PORT] [LOG OPTIONS]\n"
    "      the emulated card on a tty (USB-RS485 adapter) or PTY until SIGINT/SIGTERM;\n"
    "      --bus lcm:CHANNEL puts it on a virtual segment over LCM instead, shared with the\n"
    "      stations of other processes or machines (--lcm-url, else $LCM_DEFAULT_URL, else\n"
    "      LCM's default udpm://239.255.76.67:7667?ttl=0);\n"
    "      --address is the DIP-switch setting (default 4; above 125 the card stays off the bus);\n"
    "      --inverter: the emulated MOVIDRIVE (default; --eeprom keeps its parameters in FILE),\n"
    "      none (PI words echo PO words), or a MOVIDRIVE on SBus through SocketCAN;\n"
    "      --card-nvm keeps the card's own data (I&M1..I&M4) in FILE;\n"
    "      several addresses (4-9, 3,5,7) put a line of cards, each with its own drive, on\n"
    "      the one port: --eeprom and --card-nvm then name directories (driveN.ee, cardN.nvm)\n"
    "  master --port DEV|--bus lcm:CHANNEL [--lcm-url URL] --address N|N-M,... --config HEX\n"
    "         [--prm HEX] [--cycles N] [--baud RATE] [--ident N] [--watchdog MS]\n"
    "         [--master-address N] [--slot-time MS] [--outputs HEX] [--timeout S]\n"
    "         [--capture FILE] [--verbose] [--reset-fault] [--http [ADDR:]PORT] [LOG OPTIONS]\n"
    "      the built-in class-1 master against one slave or several (up to 32, e.g. 3-34 or\n"
    "      3,5,7-9, all with the same configuration); exit 0 once each ran N cycles (default\n"
    "      100; 0: run until SIGINT, exit 0) in data exchange. --verbose logs the inputs,\n"
    "      decoded, whenever they change. --prm is the user parameter part (Set_Prm from octet 7);\n"
    "      default for ident 0x6003: 00 00 00 06 81 00 00 01 01. Like a PLC going to STOP, it\n"
    "      leaves (after --cycles, or on SIGINT/SIGTERM) with Global_Control Clear_Data and zero\n"
    "      outputs for 3 cycles; --reset-fault acknowledges a drive fault at start (control\n"
    "      word bit 6 set, then cleared; the drive needs P101 = FIELDBUS)\n"
    "  inverter --can IFACE [--sbus-address N] [--eeprom FILE] [--duration S] [--channel2]\n"
    "           [--quiet]\n"
    "      the emulated MOVIDRIVE on SBus (SocketCAN, e.g. vcan0) until SIGINT/SIGTERM; prints\n"
    "      every parameter service and state change. --sbus-address is P813 (0..63, default 0);\n"
    "      --eeprom keeps non-volatile parameters in FILE across runs\n"
    "  param --port DEV|--bus lcm:CHANNEL [--lcm-url URL] --address N\n"
    "        [--via channel|movilink|profidrive|c2] [--baud RATE] [--master-address N]\n"
    "        [--timeout S] [--json] [--capture FILE] [--verbose]\n"
    "        read PARAM [PARAM ...] | write PARAM VALUE [--volatile] | im0\n"
    "      one parameter service against the card on a tty, or as a master on an LCM segment\n"
    "      (--bus, --lcm-url as for slave). PARAM: an index (8461, 0x210D), a P-number\n"
    "      (P100), a name or a unique part of one (\"setpoint source\"), or an IPOS variable\n"
    "      (H12 = 11012). VALUE: a raw number (3, -5, 0x10), an enumeration text (FIELDBUS) or\n"
    "      a value in the parameter's unit (300.5, \"300 rpm\"). Results name the parameter\n"
    "      (P100 setpoint source = 3 (FIELDBUS)). channel (default) brings the slave up with\n"
    "      Param + 3 PD and uses the cyclic 8-byte channel; movilink / profidrive bring it up\n"
    "      with DP-V1 parameters and use class-1 data set 47 (request id 0x40 / 0x01, write\n"
    "      0x02 non-volatile); c2 opens a class-2 connection (no start-up), id 0x40, aborts it.\n"
    "      im0 reads I&M0 (class 1, or --via c2). --volatile: write to RAM only (movilink,\n"
    "      channel). read with up to 19 indices: one data set 47 request (not channel), one\n"
    "      result line each. --master-address: default 2 (1 with c2). Exit 0 when every result\n"
    "      is positive, 1 on a negative one or none within --timeout (default 10 s), 2 on a bad\n"
    "      command line or an unknown PARAM; --json: one JSON object per result (p_number,\n"
    "      name, value, text ...)\n"
    "  convert IN OUT [--format pcap|pcapng|text] [--linktype profibus|user0] [--ns]\n"
    "          [--in-format pcap|pcapng|text|lcm] [--channel NAME] [--quiet]\n"
    "      copies a capture into another format or link type (e.g. user0 for the Wireshark\n"
    "      dissector in tools/wireshark/); the output format defaults to OUT's extension\n"
    "      (.pcapng, .txt, else pcap); damaged records are copied and reported\n"
    "  replay FILE [--address N] [--check] [--speed real|max] [--baud RATE]\n"
    "         [--format pcap|pcapng|text|lcm] [--inverter sim|none] [--inverter-delay US]\n"
    "         [--fixed-baud] [--verbose] [--lcm URL] [--channel NAME]\n"
    "      a bus capture played against the emulated card at its recorded times (the card's\n"
    "      own recorded answers are left out: it makes its own); --check compares every reply\n"
    "      with the recorded one and reports the first difference and counts per service\n"
    "      (exit 0: all match, 1: a difference or a damaged file, 2: bad command line or\n"
    "      unreadable file). The address comes from the capture unless given; the rate from\n"
    "      --baud, else the capture, else the lowest its timing allows. --lcm publishes the\n"
    "      replay's telegrams, card state and parameter services with the capture's times\n"
    "      (file://OUT.lcm?mode=w writes an LCM log at any speed). --channel: an LCM log's\n"
    "      telegram channel to read ('*' all; default DFP_TELEGRAM when the log has it beside\n"
    "      others, else all; also for convert). docs/replay.md\n"
    "  record --capture FILE --cycles N [--baud RATE] [--address N] [--dpv1] [--faults]\n"
    "         [--foreign] [--param-every N] [--inverter sim|none] [--capture-format ...]\n"
    "      the built-in master and the card on the simulated bus for N Data_Exchange cycles,\n"
    "      parameter-channel services every N cycles (default 10, 0: none), every telegram\n"
    "      into FILE: --dpv1 adds data set 47 (class 1) and a class-2 connection, --faults a\n"
    "      watchdog expiry and a wrong configuration, --foreign a second slave and master\n"
    "  check-cfg HEX\n"
    "      would the card accept this Chk_Cfg configuration?\n"
    "\n"
    "RATE: 9600 19200 45450 93750 187500 500000 1.5M 3M 6M 12M (also 19.2k ...).\n"
    "--capture FILE writes every telegram: pcap (default), pcapng (.pcapng) or text (.txt), or\n"
    "  as --capture-format pcap|pcapng|text says; link type PROFIBUS_DL (257) unless\n"
    "  --capture-linktype user0 (147, for Wireshark); --capture-ns: nanosecond timestamps.\n"
    "  docs/captures.md describes the formats.\n"
    "--http [ADDR:]PORT serves the control API (JSON, docs/api.md) and the front panel at /;\n"
    "  127.0.0.1 unless ADDR is given. A taken port is an error (exit 2).\n"
    "LOG OPTIONS: --quiet (warnings and errors only), --log-level error|warn|info|debug (debug\n"
    "  adds every baud-search step), --timestamps bus|wall (ms since start, or clock time).\n"
    "--lcm URL publishes the card's telegrams, state and parameter services to LCM (channels\n"
    "DFP_TELEGRAM, DFP_CARD_STATE, DFP_PARAM; sim_host/lcm/README.md).\n";

static int cmd_check_cfg(int argc, char **argv)
{
    if (argc != 3) {
        cli_error("check-cfg takes one argument: the configuration octets in hex");
        return EXIT_USAGE;
    }
    uint8_t cfg[244];
    size_t len = 0;
    if (!cli_hex("check-cfg", argv[2], cfg, sizeof cfg, &len)) {
        return EXIT_USAGE;
    }
    char hex[3 * sizeof cfg + 1];
    size_t n = 0;
    for (size_t i = 0; i < len; i++) {
        n += (size_t)snprintf(hex + n, sizeof hex - n, "%02X", cfg[i]);
    }
    dfp21b_pd_cfg_t pd;
    if (dfp21b_check_cfg(cfg, len, &pd)) {
        unsigned bytes = (pd.param_channel ? 8u : 0u) + 2u * pd.pd_words;
        printf("%s: accepted, %s%u PD, %u bytes out, %u bytes in\n", hex,
               pd.param_channel ? "param channel + " : "", pd.pd_words, bytes, bytes);
        return 0;
    }
    uint16_t out_len = 0;
    uint16_t in_len = 0;
    if (dp_cfg_io_lengths(cfg, len, &out_len, &in_len) && out_len != in_len) {
        printf("%s: refused (Cfg_Fault, P090 = 0PD): %u bytes out but %u in; the card needs "
               "equal lengths\n", hex, out_len, in_len);
    } else {
        printf("%s: refused (Cfg_Fault, P090 = 0PD): not one of the card's configurations "
               "(optional parameter channel F3/B7 or 00, then 1..10 consistent PD words)\n", hex);
    }
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 ||
        strcmp(argv[1], "help") == 0) {
        fputs(usage, argc < 2 ? stderr : stdout);
        return argc < 2 ? EXIT_USAGE : 0;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "demo") == 0) return cmd_demo(argc, argv);
    if (strcmp(cmd, "slave") == 0) return cmd_slave(argc, argv);
    if (strcmp(cmd, "master") == 0) return cmd_master(argc, argv);
    if (strcmp(cmd, "check-cfg") == 0) return cmd_check_cfg(argc, argv);
    if (strcmp(cmd, "inverter") == 0) return cmd_inverter(argc, argv);
    if (strcmp(cmd, "param") == 0) return cmd_param(argc, argv);
    if (strcmp(cmd, "convert") == 0) return cmd_convert(argc, argv);
    if (strcmp(cmd, "replay") == 0) return cmd_replay(argc, argv);
    if (strcmp(cmd, "record") == 0) return cmd_record(argc, argv);
    cli_error("unknown command '%s' (commands: demo, slave, master, inverter, param, convert, "
              "replay, record, check-cfg; see --help)", cmd);
    return EXIT_USAGE;
}
