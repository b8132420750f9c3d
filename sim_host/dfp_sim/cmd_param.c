/* dfp-sim param: one parameter service against a DFP21B (or dfp-sim slave) on a tty/PTY, or a
 * read of up to 19 parameters in one data set 47 request (as a PLC's block read does), by one of
 * four paths:
 *   channel     DP start-up with "Param + 3 PD" (F3 F2), the cyclic 8-byte MOVILINK channel
 *   movilink    DP start-up with DP-V1 parameters, class-1 data set 47, request id 0x40
 *   profidrive  the same with request id 0x01 (read) / 0x02 (change, non-volatile)
 *   c2          a class-2 connection (no start-up), data set 47 with id 0x40, then Abort
 * and I&M0 through class 1 or class 2. A parameter is named by index, P-number, name
 * (movidrive_names.h) or IPOS variable Hn; results carry the name and the value in its unit or
 * enumeration text. Exit 0 when every result is positive, 1 on a negative one or no result in time,
 * 2 on a bad command line. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bus_opts.h"
#include "cli.h"
#include "commands.h"
#include "lcm_bridge/lcm_segment.h"
#include "medium.h"
#include "movidrive/movidrive_names.h"
#include "param_run.h"
#include "report.h"
#include "rig/rig.h"
#include "sim_hal/host_clock.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

static const uint8_t cfg_param_3pd[] = {0xF3, 0xF2};

static run_t run;
static rig_t rig; /* large: static storage, as rig.h asks */
static dp_master_t *master; /* the rig's */
static report_t rep;

/* A failure of the whole request (no answer, a negative DP-V1 response, ...): every parameter
 * in it gets it. */
static void set_result_error(const char *code, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void set_result_error(const char *code, const char *fmt, ...)
{
    char text[sizeof run.r[0].text];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    run.ok = false;
    for (unsigned i = 0; i < run.n; i++) {
        run.r[i].ok = false;
        snprintf(run.r[i].error, sizeof run.r[i].error, "%s", code);
        snprintf(run.r[i].text, sizeof run.r[i].text, "%s", text);
    }
}

/* ---- results of the paths ------------------------------------------------------------------ */

static void finish_call(void)
{
    dp_master_call_t *c = &run.call;
    if (!c->ok) {
        if (c->dpv1_negative) {
            char code[32];
            snprintf(code, sizeof code, "DP-V1 0x%02X", c->neg_code1);
            set_result_error(code, "%s", c->error);
        } else {
            set_result_error("failed", "%s", c->error);
        }
        return;
    }
    char err[160];
    if (run.op == OP_IM0) {
        if (!dp_master_im0_decode(c->data, c->len, &run.im0, err, sizeof err)) {
            set_result_error("failed", "%s", err);
            return;
        }
        run.ok = run.r[0].ok = true;
        return;
    }
    dp_master_ds47_rsp_t rsp;
    if (!dp_master_ds47_parse(&run.req, c->data, c->len, &rsp, err, sizeof err)) {
        set_result_error("failed", "malformed data set 47 response: %s", err);
        return;
    }
    run.ok = true;
    for (unsigned i = 0; i < run.n; i++) {
        param_result_t *r = &run.r[i];
        r->ok = rsp.p[i].ok;
        if (!r->ok) {
            run.ok = false;
            snprintf(r->error, sizeof r->error, "0x%04X", rsp.p[i].error);
            dp_master_ds47_error_text(rsp.id, rsp.p[i].error, r->text, sizeof r->text);
            continue;
        }
        r->have_value = rsp.p[i].has_value;
        r->value = rsp.p[i].value;
    }
}

static void finish_channel(const uint8_t *in)
{
    if ((in[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        uint8_t cls = in[4];
        uint16_t v;
        if (cls == ML_CLASS_OTHER) {
            v = (uint16_t)(0x0800u | in[7]);
        } else {
            v = (uint16_t)((cls << 8) | in[5]);
        }
        char code[16];
        char text[160];
        snprintf(code, sizeof code, "0x%04X", v);
        ml_error_text(in, text, sizeof text);
        set_result_error(code, "%s", text);
        return;
    }
    run.ok = run.r[0].ok = true;
    run.r[0].have_value = run.op == OP_READ;
    run.r[0].value = ml_data(in);
}

static void c2_opened(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    (void)ctx;
    (void)now;
    run.c2_open_done = true;
    run.c2_open_ok = r->ok;
}

static void c2_aborted(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    (void)ctx;
    (void)r;
    (void)now;
    run.c2_abort_done = true;
}

static dp_master_ds47_req_t build_request(void)
{
    dp_master_ds47_req_t q = {.ref = 1, .axis = 0, .n = run.n};
    for (unsigned i = 0; i < run.n; i++) {
        q.p[i].number = run.index[i];
        q.p[i].value = run.value;
        if (run.via == VIA_PROFIDRIVE) {
            q.p[i].attribute = DS47_ATTR_VALUE;
        } else {
            q.p[i].attribute = run.op == OP_READ ? DS47_ATTR_ML_READ
                               : run.volatile_write ? DS47_ATTR_ML_WRITE_VOLATILE
                                                    : DS47_ATTR_ML_WRITE;
        }
    }
    if (run.via == VIA_PROFIDRIVE) {
        q.id = run.op == OP_WRITE ? DS47_ID_CHANGE : DS47_ID_REQUEST;
    } else {
        q.id = DS47_ID_MOVILINK;
    }
    return q;
}

static bool start_call(dp_master_acyc_port_t p, hal_time_us_t now)
{
    memset(&run.call, 0, sizeof run.call);
    int rc;
    if (run.op == OP_IM0) {
        rc = dp_master_im0_start(&run.call, p, NULL, NULL, now);
    } else {
        run.req = build_request();
        rc = dp_master_ds47_start(&run.call, p, &run.req, NULL, NULL, now);
    }
    if (rc != 0) {
        set_result_error("failed", "the request could not be queued");
        return false;
    }
    rig_wake(&rig);
    return true;
}

/* One look at the state after the runner ran; moves the run along. */
static void step(void)
{
    hal_time_us_t now = tty_now_us();
    dp_master_slave_t *s = master->num_slaves > 0u ? &master->slaves[0] : NULL;
    switch (run.stage) {
    case ST_START:
        if (run.via == VIA_C2) {
            if (!run.c2_open_done) {
                return;
            }
            if (!run.c2_open_ok) {
                set_result_error("failed", "%s", dp_master_c2_error(&run.c2));
                run.stage = ST_DONE;
                return;
            }
            run.stage = start_call(dp_master_c2_port(&run.c2), now) ? ST_RUNNING : ST_ABORTING;
            if (run.stage == ST_ABORTING) {
                (void)dp_master_c2_abort(&run.c2, 0, c2_aborted, NULL, now);
                rig_wake(&rig);
            }
            return;
        }
        /* Without class 2 the slave was added before the run started; s is never NULL here. */
        if (s == NULL || s->phase != DP_MASTER_PHASE_DATA_EXCH) {
            return;
        }
        if (run.via == VIA_CHANNEL) {
            /* First see the card's reply catch up with what we send: our first outputs are
             * zeros, "no service" with handshake 0, which the card acknowledges if its channel
             * stood at 1 from an earlier master. Only then toggle relative to that reply. */
            if (s->cycles == 0u || s->inputs_len < ML_TELEGRAM_LEN ||
                ((s->inputs[0] ^ run.out[0]) & ML_MGMT_HANDSHAKE) != 0u) {
                return;
            }
            uint8_t svc = run.op == OP_READ ? ML_SVC_READ
                          : run.volatile_write ? ML_SVC_WRITE_VOLATILE : ML_SVC_WRITE;
            dp_master_param_sync(&run.pc, s->inputs);
            dp_master_param_start(&run.pc, svc, run.index[0], run.value, run.out);
            dp_master_set_outputs(master, 0, run.out, sizeof run.out);
            run.stage = ST_RUNNING;
            return;
        }
        run.stage = start_call(dp_master_c1_port(master, 0), now) ? ST_RUNNING : ST_DONE;
        return;
    case ST_RUNNING:
        if (run.via == VIA_CHANNEL) {
            if (s != NULL && dp_master_param_done(&run.pc, s->inputs)) {
                finish_channel(s->inputs);
                run.stage = ST_DONE;
            }
            return;
        }
        if (!dp_master_call_done(&run.call)) {
            return;
        }
        finish_call();
        if (run.via == VIA_C2 && dp_master_c2_state(&run.c2) != DP_MASTER_C2_CLOSED &&
            dp_master_c2_abort(&run.c2, 0, c2_aborted, NULL, now) == 0) {
            rig_wake(&rig);
            run.stage = ST_ABORTING;
            return;
        }
        run.stage = ST_DONE;
        return;
    case ST_ABORTING:
        if (run.c2_abort_done || dp_master_c2_state(&run.c2) == DP_MASTER_C2_CLOSED) {
            run.stage = ST_DONE;
        }
        return;
    case ST_DONE:
        return;
    }
}

static void timeout_text(uint32_t timeout_s)
{
    dp_master_slave_t *s = master->num_slaves > 0u ? &master->slaves[0] : NULL;
    if (run.stage == ST_START && s != NULL) {
        /* In a token ring the start-up moves one telegram per token visit, so the timeout may
         * find the slave anywhere in its next attempt: the reason of the last one still holds. */
        bool why = s->phase != DP_MASTER_PHASE_FDL_STATUS && s->fault[0] != '\0';
        bool backoff = s->phase == DP_MASTER_PHASE_BACKOFF;
        set_result_error("timeout", "no result within %u s: slave %u did not reach data "
                         "exchange (phase %s%s%s)", timeout_s, s->cfg.address,
                         dp_master_phase_name(s->phase),
                         !why ? "" : backoff ? ": " : " again after: ", why ? s->fault : "");
    } else if (run.stage == ST_START) {
        set_result_error("timeout", "no result within %u s: the class-2 connection did not "
                         "open (%s)", timeout_s,
                         dp_master_c2_state_name(dp_master_c2_state(&run.c2)));
    } else if (run.via == VIA_CHANNEL) {
        set_result_error("timeout", "no result within %u s: no reply with the request's "
                         "handshake in the cyclic channel", timeout_s);
    } else {
        set_result_error("timeout", "no result within %u s (%u Read.req, %u answered B5)",
                         timeout_s, run.call.reads, run.call.busy);
    }
}

static hal_time_us_t master_timer(void *ctx, hal_time_us_t now)
{
    return dp_master_poll(ctx, now);
}

/* ---- command line ------------------------------------------------------------------------ */

/* A raw 32-bit number (decimal, -N, 0xHEX) for any index; for a named parameter also an
 * enumeration text ("FIELDBUS") or a value in its unit ("300.5", "300 rpm"). */
static bool parse_value(uint16_t index, const char *text, uint32_t *out)
{
    char err[200];
    int32_t raw = 0;
    if (!movidrive_value_parse(movidrive_param_info(index), text, &raw, err, sizeof err)) {
        cli_error("param: VALUE %s", err);
        return false;
    }
    *out = (uint32_t)raw;
    return true;
}

/* INDEX as a number (any, whether the table has it or not), Hn (IPOS variable), a P-number or
 * a name. */
static bool parse_index(const char *text, uint16_t *index)
{
    uint32_t v = 0;
    if (text[0] >= '0' && text[0] <= '9') {
        char *end = NULL;
        (void)strtoul(text, &end, 0);
        if (*end == '\0') {
            if (!cli_u32("INDEX", text, 0, 65535, &v)) return false;
            *index = (uint16_t)v;
            return true;
        }
    }
    if ((text[0] == 'H' || text[0] == 'h') && text[1] >= '0' && text[1] <= '9') {
        char *end = NULL;
        errno = 0;
        unsigned long n = strtoul(text + 1, &end, 10);
        if (*end != '\0' || errno != 0 || n >= IPOS_COUNT) {
            cli_error("param: '%s' is not an IPOS variable (H0..H511)", text);
            return false;
        }
        *index = (uint16_t)(IPOS_FIRST + n);
        return true;
    }
    char err[256];
    const movidrive_param_info_t *p = movidrive_param_find(text, err, sizeof err);
    if (p == NULL) {
        cli_error("param: %s", err);
        return false;
    }
    *index = p->index;
    return true;
}

static uint64_t clock_now(void *ctx)
{
    return host_clock_mono_ns() - *(uint64_t *)ctx;
}

/* The command line as given. */
typedef struct param_opts {
    medium_opts_t med;
    bus_opts_t bus;
    fdl_bus_params_t ring; /* from bus */
    capture_opts_t capture;
    uint32_t address;
    bool have_address;
    uint32_t own;
    bool have_own;
    uint32_t baud;
    uint32_t timeout_s;
    via_t via;
    bool via_given;
    bool volatile_write;
    bool json;
    bool verbose;
    bool echo;
    const char *pos[1 + DS47_MAX_PARAMS]; /* read and its indices, or write INDEX VALUE */
    int npos;
} param_opts_t;

/* An operand: read, write or im0 and what follows it. */
static bool param_operand(void *opts, const char *arg)
{
    param_opts_t *o = opts;
    if (o->npos == (int)(sizeof o->pos / sizeof o->pos[0])) {
        cli_error("param: too many arguments ('%s'%s)", arg,
                  strcmp(o->pos[0], "read") == 0 ? "; a read takes up to 19 indices" : "");
        _Static_assert(DS47_MAX_PARAMS == 19u, "the message above names 19");
        return false;
    }
    o->pos[o->npos++] = arg;
    return true;
}

static const cli_choice_t param_vias[] = {
    {"channel", VIA_CHANNEL, false},
    {"movilink", VIA_MOVILINK, false},
    {"profidrive", VIA_PROFIDRIVE, false},
    {"c2", VIA_C2, false},
    {NULL, 0, false},
};

#define PARAM(field) offsetof(param_opts_t, field)

static const cli_opt_t param_options[] = {
    {CLI_OPT("--address", "N", CLI_U32, PARAM(address)), .min = 0, .max = 125,
     .seen = CLI_SEEN(param_opts_t, have_address)},
    {CLI_OPT("--via", "channel|movilink|profidrive|c2", CLI_CHOICE, PARAM(via)),
     .choices = param_vias, .bad = "param: --via '%s': use channel, movilink, profidrive or c2",
     .seen = CLI_SEEN(param_opts_t, via_given)},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, PARAM(baud))},
    {CLI_OPT("--master-address", "N", CLI_U32, PARAM(own)), .min = 0, .max = 126,
     .seen = CLI_SEEN(param_opts_t, have_own)},
    {CLI_OPT("--timeout", "S", CLI_U32, PARAM(timeout_s)), .min = 1, .max = 3600u},
    {CLI_OPT("--json", NULL, CLI_FLAG, PARAM(json))},
    {CLI_OPT("--verbose", NULL, CLI_FLAG, PARAM(verbose))},
    {CLI_OPT("--volatile", NULL, CLI_FLAG, PARAM(volatile_write))},
    {CLI_OPT("--echo-suppress", NULL, CLI_FLAG, PARAM(echo))},
};

static const cli_group_t param_groups[] = {
    {medium_options, CLI_COUNT(medium_options), PARAM(med)},
    {param_options, CLI_COUNT(param_options), 0},
    {bus_options, CLI_COUNT(bus_options), PARAM(bus)},
    {capture_options, CLI_COUNT(capture_options), PARAM(capture)},
};

const cli_command_t cli_param = {.name = "param", .groups = param_groups,
                                 .n_groups = CLI_COUNT(param_groups),
                                 .operands = CLI_OPERANDS_DD, .operand = param_operand,
                                 .words = "read write im0"};

/* read INDEX..., write INDEX VALUE or im0: the operation and its argument count. */
static bool param_operation(const param_opts_t *o)
{
    const char *what = o->pos[0];
    if (strcmp(what, "read") == 0) {
        run.op = OP_READ;
        if (o->npos >= 2) return true;
        cli_error("param: read takes the parameter INDEX, or up to %u of them for one data "
                  "set 47 request (e.g. read 8300, read P100, read 8318 8319 8320 --via "
                  "movilink)",
                  DS47_MAX_PARAMS);
        return false;
    }
    if (strcmp(what, "write") == 0) {
        run.op = OP_WRITE;
        if (o->npos == 3) return true;
        cli_error("param: write takes two arguments, INDEX and VALUE (e.g. write 8489 1500, "
                  "write P100 FIELDBUS)");
        return false;
    }
    if (strcmp(what, "im0") != 0) {
        cli_error("param: unknown operation '%s' (read, write or im0)", what);
        return false;
    }
    run.op = OP_IM0;
    if (o->npos != 1) {
        cli_error("param: im0 takes no argument ('%s')", o->pos[1]);
        return false;
    }
    if (!o->via_given) {
        run.via = VIA_MOVILINK; /* class 1 */
    } else if (run.via == VIA_CHANNEL) {
        cli_error("param: im0 needs DP-V1, which --via channel does not use: leave --via out "
                  "(im0 then uses movilink) or give --via movilink, profidrive or c2");
        return false;
    }
    return true;
}

/* The combinations a path or an operation does not allow. False after reporting. */
static bool param_combination(param_opts_t *o)
{
    if (run.n > 1u && run.via == VIA_CHANNEL) {
        cli_error("param: the cyclic channel carries one service at a time; read several "
                  "indices with --via movilink, profidrive or c2 (one data set 47 request)");
        return false;
    }
    if (run.volatile_write && run.op != OP_WRITE) {
        cli_error("param: --volatile belongs to write");
        return false;
    }
    if (run.volatile_write && run.via != VIA_MOVILINK && run.via != VIA_CHANNEL) {
        cli_error("param: --volatile works with --via movilink or channel (PROFIdrive change "
                  "parameter always writes non-volatile)");
        return false;
    }
    if (!o->have_own) {
        o->own = run.via == VIA_C2 ? 1u : 2u;
    }
    if (o->own == o->address) {
        cli_error("param: --master-address %u is the slave's address", o->own);
        return false;
    }
    return true;
}

/* The command line into o and run: 0, or EXIT_USAGE after reporting. */
static int param_parse(param_opts_t *o, int argc, char **argv)
{
    *o = (param_opts_t){.baud = 19200, .timeout_s = 10};
    bus_opts_defaults(&o->bus);
    if (cli_parse(&cli_param, argc, argv, o) != 0) return EXIT_USAGE;
    run.via = o->via;
    run.volatile_write = o->volatile_write;
    run.json = o->json;
    if ((o->med.dev == NULL && o->med.bus == NULL) || !o->have_address) {
        cli_error("param: --port DEV and --address N are required (or --bus lcm:CHANNEL instead "
                  "of --port)");
        return EXIT_USAGE;
    }
    const cli_file_t capture = {"--capture", o->capture.path, false};
    if (!medium_check(&o->med, "param") || !cli_no_links("param", &capture, 1u) ||
        !bus_opts_apply(&o->bus, "param", o->baud, true, &o->ring)) {
        return EXIT_USAGE;
    }
    if (o->npos == 0) {
        cli_error("param: say what to do: read INDEX [INDEX ...], write INDEX VALUE or im0");
        return EXIT_USAGE;
    }
    if (!param_operation(o)) return EXIT_USAGE;
    run.n = run.op == OP_READ ? (uint8_t)(o->npos - 1) : 1u;
    for (unsigned i = 0; run.op != OP_IM0 && i < run.n; i++) {
        if (!parse_index(o->pos[1 + i], &run.index[i])) return EXIT_USAGE;
    }
    if (run.op == OP_WRITE && !parse_value(run.index[0], o->pos[2], &run.value)) {
        return EXIT_USAGE;
    }
    return param_combination(o) && bus_opts_own_ok(&o->ring, "param", "--master-address", o->own)
               ? 0
               : EXIT_USAGE;
}

/* A keyed segment's drops and totals, among the command's other lines. */
static void param_segment_log(void *ctx, const char *line)
{
    report_line(ctx, "lcm", "%s", line);
}

/* The medium and the capture. Returns false after reporting (nothing left open). */
static bool param_open(const param_opts_t *o)
{
    char err[320];
    const medium_opts_t *m = &o->med;
    rig_cfg_t rc = {.medium = m->bus != NULL ? RIG_MEDIUM_LCM : RIG_MEDIUM_TTY,
                    .device = m->dev,
                    .lcm_channel = m->bus != NULL ? dfp_lcm_segment_channel(m->bus) : NULL,
                    .lcm_url = m->lcm_url,
                    .lcm_station_address = (int16_t)o->own,
                    .lcm_key = medium_key(m),
                    .baud = o->baud,
                    .echo_suppress = o->echo};
    rig_init(&rig, &rc);
    rig_tap_t tap = {.ctx = &rep, .frame = report_tap,
                     .master_event = o->verbose ? report_master_event : NULL};
    (void)rig_add_tap(&rig, &tap);
    if (rig_open(&rig, err, sizeof err) != 0) {
        cli_error("%s", err);
        return false;
    }
    if (m->bus != NULL) {
        dfp_lcm_segment_set_log(&rig.segment, param_segment_log, &rep);
    }
    static uint64_t t0;
    t0 = host_clock_mono_ns();
    rep.now_ns = clock_now;
    rep.now_ctx = &t0;
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts);
    rep.capture_direction = true;
    if (!report_open_capture(&rep, &o->capture,
                             (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec)) {
        rig_close(&rig);
        return false;
    }
    cli_catch_stop_signals();
    return true;
}

/* The master with the slave (class 1, started up with Param + 3 PD) or with the class-2
 * connection, on the rig's medium. False after reporting (a fresh runner always has room, so
 * this does not happen in practice). */
static bool param_master(const param_opts_t *o)
{
    dp_master_cfg_t mc = {.address = (uint8_t)o->own, .baud = o->baud, .strict_timing = false,
                          .token_ring = true, .bus = o->ring};
    master = rig_add_master(&rig, &mc, tty_now_us());
    if (master == NULL) {
        cli_error("param: the master could not join the medium");
        return false;
    }
    if (run.via != VIA_C2) {
        dp_master_slave_cfg_t sc = {.address = (uint8_t)o->address};
        if (run.via == VIA_CHANNEL) {
            sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 1000,
                                                dfp21b_user_prm_default,
                                                sizeof dfp21b_user_prm_default);
        } else {
            sc.prm_len = (uint8_t)dp_master_build_prm_dpv1(sc.prm, DFP21B_IDENT, 1000,
                                                     dfp21b_user_prm_default,
                                                     sizeof dfp21b_user_prm_default);
        }
        memcpy(sc.cfg, cfg_param_3pd, sizeof cfg_param_3pd);
        sc.cfg_len = sizeof cfg_param_3pd;
        (void)dp_master_add_slave(master, &sc);
    } else {
        dp_master_c2_cfg_t cc = {.slave = (uint8_t)o->address, .address = (uint8_t)o->own};
        dp_master_c2_init(&run.c2, &cc);
        (void)dp_master_add_c2(master, &run.c2);
        (void)dp_master_c2_open(&run.c2, c2_opened, NULL, tty_now_us());
    }
    /* so a new request goes at once */
    (void)rig_add_timer(&rig, master_timer, master);
    return true;
}

/* Until the result, --timeout, a signal or a medium failure; every parameter then has its
 * result. */
static void param_run(const param_opts_t *o)
{
    uint64_t end_ns = host_clock_mono_ns() + (uint64_t)o->timeout_s * 1000000000ull;
    const char *fail = NULL;
    while (run.stage != ST_DONE && !cli_stop && host_clock_mono_ns() < end_ns) {
        if (rig_run_until(&rig, tty_now_us() + 5000u, &cli_stop) < 0) {
            fail = rig_error(&rig);
            break;
        }
        step();
    }
    if (run.stage == ST_DONE) {
        return;
    }
    if (fail != NULL) {
        set_result_error("failed", "%s", fail);
    } else if (cli_stop) {
        set_result_error("failed", "interrupted");
    } else {
        timeout_text(o->timeout_s);
    }
}

int cmd_param(int argc, char **argv)
{
    static param_opts_t o;
    memset(&run, 0, sizeof run);
    int rc = param_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    if (!param_open(&o)) {
        return 1;
    }
    if (!param_master(&o)) {
        rig_close(&rig);
        (void)report_close_capture(&rep);
        return 1;
    }
    param_run(&o);
    param_print_results(&run);
    rig_close(&rig);
    if (report_close_capture(&rep) != 0) {
        return 1;
    }
    return run.ok ? 0 : 1;
}
