/* dfp-sim param: one parameter service against a DFP21B (or dfp-sim slave) on a tty/PTY, or a
 * read of up to 19 parameters in one data set 47 request (as a PLC's block read does), by one of
 * four paths:
 *   channel     DP start-up with "Param + 3 PD" (F3 F2), the cyclic 8-byte MOVILINK channel
 *   movilink    DP start-up with DP-V1 parameters, class-1 data set 47, request id 0x40
 *   profidrive  the same with request id 0x01 (read) / 0x02 (change, non-volatile)
 *   c2          a class-2 connection (no start-up), data set 47 with id 0x40, then Abort
 * and I&M0 through class 1 or class 2. A parameter is named by index, P-number, name (md_names.h)
 * or IPOS variable Hn; results carry the name and the value in its unit or enumeration text.
 * Exit 0 when every result is positive, 1 on a negative one or no result in time, 2 on a bad
 * command line. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"
#include "movidrive/md_names.h"
#include "report.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"
#include "sim_hal/host_clock.h"

typedef enum via { VIA_CHANNEL = 0, VIA_MOVILINK, VIA_PROFIDRIVE, VIA_C2 } via_t;
typedef enum op { OP_READ = 0, OP_WRITE, OP_IM0 } op_t;

static const char *const via_names[] = {"channel", "movilink", "profidrive", "c2"};
static const char *const op_names[] = {"read", "write", "im0"};

static const uint8_t cfg_param_3pd[] = {0xF3, 0xF2};

/* ---- the run ----------------------------------------------------------------------------- */

typedef enum stage {
    ST_START = 0,  /* waiting for data exchange / opening the connection */
    ST_RUNNING,    /* the service is on its way */
    ST_ABORTING,   /* class 2: closing the connection after the result */
    ST_DONE,
} stage_t;

/* One parameter's outcome: a data set 47 answer fails or succeeds parameter by parameter. */
typedef struct param_result {
    bool ok;
    bool have_value;
    uint32_t value;
    char error[32];  /* "0x0815", "DP-V1 0xB0", "timeout", "failed" */
    char text[256];
} param_result_t;

typedef struct run {
    op_t op;
    via_t via;
    uint8_t n;  /* parameters: 1, or up to DS47_MAX_PARAMS for a data set 47 read */
    uint16_t index[DS47_MAX_PARAMS];
    uint32_t value;
    bool volatile_write;
    bool json;
    stage_t stage;
    /* result: the whole run's (ok only if every parameter's is), then each parameter's */
    bool ok;
    param_result_t r[DS47_MAX_PARAMS];
    dpm_im0_t im0;
    /* paths */
    dp_master_t master;
    dpm_param_t pc;
    uint8_t out[14];
    dpm_call_t call;
    dpm_ds47_req_t req;
    dpm_c2_t c2;
    bool c2_open_done;
    bool c2_open_ok;
    bool c2_abort_done;
    uint32_t cycles_at_start;
} run_t;

static run_t run;
static tty_port_t port;
static tty_runner_t runner;
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

/* ---- output ------------------------------------------------------------------------------ */

static void json_str(const char *key, const char *s)
{
    printf(",\"%s\":\"", key);
    for (; *s != '\0'; s++) {
        unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\') {
            printf("\\%c", ch);
        } else if (ch < 0x20u || ch >= 0x7Fu) {
            printf("\\u%04x", ch);
        } else {
            putchar(ch);
        }
    }
    putchar('"');
}

/* Copy without the blanks a fixed-width I&M text is padded with. */
static void trimmed(char *out, size_t max, const char *in)
{
    snprintf(out, max, "%s", in);
    size_t n = strlen(out);
    while (n > 0u && (out[n - 1u] == ' ' || out[n - 1u] == '\0')) {
        out[--n] = '\0';
    }
}

#define IPOS_FIRST 11000u /* H0; H0..H511 are 11000 + n */
#define IPOS_COUNT 512u

/* "P100" and "setpoint source" for a table row, "H12" and "IPOS plus variable H12" for an IPOS
 * variable; false for an index the name table lacks. */
static bool param_names(uint16_t index, const md_param_info_t **info, char *pnum, size_t pn,
                        char *name, size_t nn)
{
    *info = md_param_info(index);
    if (*info != NULL) {
        snprintf(pnum, pn, "%s", (*info)->p_number);
        snprintf(name, nn, "%s", (*info)->name);
        return true;
    }
    if (index >= IPOS_FIRST && index < IPOS_FIRST + IPOS_COUNT) {
        snprintf(pnum, pn, "H%u", index - IPOS_FIRST);
        snprintf(name, nn, "IPOS plus variable H%u", index - IPOS_FIRST);
        return true;
    }
    return false;
}

/* "P100 setpoint source = 3 (FIELDBUS)", "P076 firmware basic unit = 823947913 (0x311C7289)",
 * "P160 internal setpoint n11 = 1.500 rpm (raw 1500, 0x000005DC)": the raw value stays in
 * sight wherever the text does not show it. */
static void value_line(const md_param_info_t *info, uint32_t value, char *out, size_t n)
{
    char text[96];
    char raw[16];
    md_value_text(info, (int32_t)value, text, sizeof text);
    snprintf(raw, sizeof raw, "%d", (int32_t)value);
    if (info->num_enums > 0u) {
        snprintf(out, n, "%s %s = %s", info->p_number, info->name, text);
    } else if (strcmp(text, raw) == 0) {
        snprintf(out, n, "%s %s = %s (0x%08X)", info->p_number, info->name, text, value);
    } else {
        snprintf(out, n, "%s %s = %s (raw %s, 0x%08X)", info->p_number, info->name, text, raw,
                 value);
    }
}

/* One line (or JSON object) per parameter, in the order asked. */
static void print_param_result(unsigned i)
{
    const param_result_t *r = &run.r[i];
    const md_param_info_t *info = NULL;
    char pnum[24] = "";
    char pname[64] = "";
    bool named = run.op != OP_IM0 &&
                 param_names(run.index[i], &info, pnum, sizeof pnum, pname, sizeof pname);
    char what[64];
    if (run.op == OP_IM0) {
        snprintf(what, sizeof what, "im0 via %s", via_names[run.via]);
    } else if (run.op == OP_READ) {
        snprintf(what, sizeof what, "read %u via %s", run.index[i], via_names[run.via]);
    } else {
        snprintf(what, sizeof what, "write%s %u = %d via %s", run.volatile_write ? " volatile" : "",
                 run.index[i], (int32_t)run.value, via_names[run.via]);
    }
    char order[24];
    char serial[20];
    trimmed(order, sizeof order, run.im0.order_id);
    trimmed(serial, sizeof serial, run.im0.serial_number);
    char sw[24];
    snprintf(sw, sizeof sw, "%c%u.%u.%u", run.im0.sw_prefix != '\0' ? run.im0.sw_prefix : '?',
             run.im0.sw_major, run.im0.sw_minor, run.im0.sw_bugfix);
    if (run.json) {
        printf("{\"op\":\"%s\"", op_names[run.op]);
        if (run.op != OP_IM0) {
            printf(",\"index\":%u", run.index[i]);
        }
        if (named) {
            json_str("p_number", pnum);
            json_str("name", pname);
        }
        json_str("via", via_names[run.via]);
        char vtext[96];
        if (run.op == OP_WRITE) {
            printf(",\"volatile\":%s,\"value\":%d", run.volatile_write ? "true" : "false",
                   (int32_t)run.value);
            if (r->ok && named) {
                md_value_text(info, (int32_t)run.value, vtext, sizeof vtext);
                json_str("text", vtext);
            }
        }
        printf(",\"ok\":%s", r->ok ? "true" : "false");
        if (r->ok && r->have_value) {
            printf(",\"value\":%d,\"hex\":\"0x%08X\"", (int32_t)r->value, r->value);
            if (named && run.op == OP_READ) {
                md_value_text(info, (int32_t)r->value, vtext, sizeof vtext);
                json_str("text", vtext);
            }
        }
        if (r->ok && run.op == OP_IM0) {
            printf(",\"manufacturer_id\":%u", run.im0.manufacturer_id);
            char hex[8];
            snprintf(hex, sizeof hex, "0x%04X", run.im0.manufacturer_id);
            json_str("manufacturer", hex);
            json_str("order_id", order);
            json_str("serial_number", serial);
            printf(",\"hardware_revision\":%u", run.im0.hardware_revision);
            json_str("software_revision", sw);
            printf(",\"rev_counter\":%u,\"profile_id\":%u,\"profile_specific_type\":%u",
                   run.im0.rev_counter, run.im0.profile_id, run.im0.profile_specific_type);
            snprintf(hex, sizeof hex, "%u.%u", run.im0.im_version_major,
                     run.im0.im_version_minor);
            json_str("im_version", hex);
            snprintf(hex, sizeof hex, "0x%04X", run.im0.im_supported);
            json_str("im_supported", hex);
        }
        if (!r->ok) {
            json_str("error", r->error);
            json_str("text", r->text);
        }
        printf("}\n");
        return;
    }
    if (!r->ok) {
        printf("%s: error %s: %s\n", what, r->error, r->text);
    } else if (run.op == OP_IM0) {
        printf("%s:\n"
               "  manufacturer id    0x%04X\n"
               "  order id           %s\n"
               "  serial number      %s\n"
               "  hardware revision  %u\n"
               "  software revision  %s\n"
               "  revision counter   %u\n"
               "  profile id         0x%04X (specific type 0x%04X)\n"
               "  I&M version        %u.%u, supported 0x%04X\n",
               what, run.im0.manufacturer_id, order, serial, run.im0.hardware_revision, sw,
               run.im0.rev_counter, run.im0.profile_id, run.im0.profile_specific_type,
               run.im0.im_version_major, run.im0.im_version_minor, run.im0.im_supported);
    } else if (r->have_value && info != NULL) {
        char line[200];
        value_line(info, r->value, line, sizeof line);
        printf("%s: %s\n", what, line);
    } else if (r->have_value) {
        printf("%s: %d (0x%08X)\n", what, (int32_t)r->value, r->value);
    } else if (info != NULL) {
        char line[200];
        value_line(info, run.value, line, sizeof line);
        printf("%s: ok (%s)\n", what, line);
    } else {
        printf("%s: ok\n", what);
    }
}

static void print_result(void)
{
    for (unsigned i = 0; i < run.n; i++) {
        print_param_result(i);
    }
    fflush(stdout);
}

/* ---- results of the paths ------------------------------------------------------------------ */

static void finish_call(void)
{
    dpm_call_t *c = &run.call;
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
        if (!dpm_im0_decode(c->data, c->len, &run.im0, err, sizeof err)) {
            set_result_error("failed", "%s", err);
            return;
        }
        run.ok = run.r[0].ok = true;
        return;
    }
    dpm_ds47_rsp_t rsp;
    if (!dpm_ds47_parse(&run.req, c->data, c->len, &rsp, err, sizeof err)) {
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
            dpm_ds47_error_text(rsp.id, rsp.p[i].error, r->text, sizeof r->text);
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

static void c2_opened(void *ctx, const dpm_acyc_result_t *r, hal_time_us_t now)
{
    (void)ctx;
    (void)now;
    run.c2_open_done = true;
    run.c2_open_ok = r->ok;
}

static void c2_aborted(void *ctx, const dpm_acyc_result_t *r, hal_time_us_t now)
{
    (void)ctx;
    (void)r;
    (void)now;
    run.c2_abort_done = true;
}

static dpm_ds47_req_t build_request(void)
{
    dpm_ds47_req_t q = {.ref = 1, .axis = 0, .n = run.n};
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

static bool start_call(dpm_acyc_port_t p, hal_time_us_t now)
{
    memset(&run.call, 0, sizeof run.call);
    int rc;
    if (run.op == OP_IM0) {
        rc = dpm_im0_start(&run.call, p, NULL, NULL, now);
    } else {
        run.req = build_request();
        rc = dpm_ds47_start(&run.call, p, &run.req, NULL, NULL, now);
    }
    if (rc != 0) {
        set_result_error("failed", "the request could not be queued");
        return false;
    }
    tty_runner_wake(&runner);
    return true;
}

/* One look at the state after the runner ran; moves the run along. */
static void step(void)
{
    hal_time_us_t now = tty_now_us();
    dpm_slave_t *s = run.master.num_slaves > 0u ? &run.master.slaves[0] : NULL;
    switch (run.stage) {
    case ST_START:
        if (run.via == VIA_C2) {
            if (!run.c2_open_done) {
                return;
            }
            if (!run.c2_open_ok) {
                set_result_error("failed", "%s", dpm_c2_error(&run.c2));
                run.stage = ST_DONE;
                return;
            }
            run.stage = start_call(dpm_c2_port(&run.c2), now) ? ST_RUNNING : ST_ABORTING;
            if (run.stage == ST_ABORTING) {
                (void)dpm_c2_abort(&run.c2, 0, c2_aborted, NULL, now);
                tty_runner_wake(&runner);
            }
            return;
        }
        /* Without class 2 the slave was added before the run started; s is never NULL here. */
        if (s == NULL || s->phase != DPM_PHASE_DATA_EXCH) {
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
            dpm_param_sync(&run.pc, s->inputs);
            dpm_param_start(&run.pc, svc, run.index[0], run.value, run.out);
            dp_master_set_outputs(&run.master, 0, run.out, sizeof run.out);
            run.stage = ST_RUNNING;
            return;
        }
        run.stage = start_call(dp_master_c1_port(&run.master, 0), now) ? ST_RUNNING : ST_DONE;
        return;
    case ST_RUNNING:
        if (run.via == VIA_CHANNEL) {
            if (s != NULL && dpm_param_done(&run.pc, s->inputs)) {
                finish_channel(s->inputs);
                run.stage = ST_DONE;
            }
            return;
        }
        if (!dpm_call_done(&run.call)) {
            return;
        }
        finish_call();
        if (run.via == VIA_C2 && dpm_c2_state(&run.c2) != DPM_C2_CLOSED &&
            dpm_c2_abort(&run.c2, 0, c2_aborted, NULL, now) == 0) {
            tty_runner_wake(&runner);
            run.stage = ST_ABORTING;
            return;
        }
        run.stage = ST_DONE;
        return;
    case ST_ABORTING:
        if (run.c2_abort_done || dpm_c2_state(&run.c2) == DPM_C2_CLOSED) {
            run.stage = ST_DONE;
        }
        return;
    case ST_DONE:
        return;
    }
}

static void timeout_text(uint32_t timeout_s)
{
    dpm_slave_t *s = run.master.num_slaves > 0u ? &run.master.slaves[0] : NULL;
    if (run.stage == ST_START && s != NULL) {
        set_result_error("timeout", "no result within %u s: slave %u did not reach data "
                         "exchange (phase %s)", timeout_s, s->cfg.address,
                         dpm_phase_name(s->phase));
    } else if (run.stage == ST_START) {
        set_result_error("timeout", "no result within %u s: the class-2 connection did not "
                         "open (%s)", timeout_s, dpm_c2_state_name(dpm_c2_state(&run.c2)));
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

static void quiet_event(void *ctx, const dpm_event_t *ev)
{
    (void)ctx;
    (void)ev;
}

/* ---- command line ------------------------------------------------------------------------ */

/* A raw 32-bit number (decimal, -N, 0xHEX) for any index; for a named parameter also an
 * enumeration text ("FIELDBUS") or a value in its unit ("300.5", "300 rpm"). */
static bool parse_value(uint16_t index, const char *text, uint32_t *out)
{
    char err[200];
    int32_t raw = 0;
    if (!md_value_parse(md_param_info(index), text, &raw, err, sizeof err)) {
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
    const md_param_info_t *p = md_param_find(text, err, sizeof err);
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

int cmd_param(int argc, char **argv)
{
    const char *dev = NULL;
    capture_opts_t capture = {.path = NULL};
    int copt;
    uint32_t address = 0;
    bool have_address = false;
    uint32_t own = 0;
    bool have_own = false;
    uint32_t baud = 19200;
    uint32_t timeout_s = 10;
    bool via_given = false;
    bool verbose = false;
    const char *pos[1 + DS47_MAX_PARAMS]; /* read and its indices, or write INDEX VALUE */
    int npos = 0;
    memset(&run, 0, sizeof run);
    for (int i = 2; i < argc; i++) {
        const char *v;
        const char *o = argv[i];
        if (strcmp(o, "--port") == 0) {
            if ((dev = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(o, "--address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 125, &address))
                return EXIT_USAGE;
            have_address = true;
        } else if (strcmp(o, "--master-address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 126, &own))
                return EXIT_USAGE;
            have_own = true;
        } else if (strcmp(o, "--baud") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_baud(o, v, false, &baud))
                return EXIT_USAGE;
        } else if (strcmp(o, "--timeout") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 1, 3600u, &timeout_s))
                return EXIT_USAGE;
        } else if (strcmp(o, "--via") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
            unsigned k = 0;
            while (k < 4u && strcmp(v, via_names[k]) != 0) k++;
            if (k == 4u) {
                cli_error("param: --via '%s': use channel, movilink, profidrive or c2", v);
                return EXIT_USAGE;
            }
            run.via = (via_t)k;
            via_given = true;
        } else if (strcmp(o, "--volatile") == 0) {
            run.volatile_write = true;
        } else if (strcmp(o, "--json") == 0) {
            run.json = true;
        } else if (strcmp(o, "--verbose") == 0) {
            verbose = true;
        } else if ((copt = capture_option(argc, argv, &i, &capture)) != 0) {
            if (copt < 0) return EXIT_USAGE;
        } else if (o[0] == '-' && o[1] == '-') {
            cli_error("param: unknown option '%s' (see dfp-sim --help)", o);
            return EXIT_USAGE;
        } else {
            if (npos == (int)(sizeof pos / sizeof pos[0])) {
                cli_error("param: too many arguments ('%s'%s)", o,
                          strcmp(pos[0], "read") == 0 ? "; a read takes up to 19 indices" : "");
                _Static_assert(DS47_MAX_PARAMS == 19u, "the message above names 19");
                return EXIT_USAGE;
            }
            pos[npos++] = o;
        }
    }
    if (dev == NULL || !have_address) {
        cli_error("param: --port DEV and --address N are required");
        return EXIT_USAGE;
    }
    if (npos == 0) {
        cli_error("param: say what to do: read INDEX [INDEX ...], write INDEX VALUE or im0");
        return EXIT_USAGE;
    }
    if (strcmp(pos[0], "read") == 0) {
        run.op = OP_READ;
        if (npos < 2) {
            cli_error("param: read takes the parameter INDEX, or up to %u of them for one data "
                      "set 47 request (e.g. read 8300, read P100, read 8318 8319 8320 --via "
                      "movilink)",
                      DS47_MAX_PARAMS);
            return EXIT_USAGE;
        }
    } else if (strcmp(pos[0], "write") == 0) {
        run.op = OP_WRITE;
        if (npos != 3) {
            cli_error("param: write takes two arguments, INDEX and VALUE (e.g. write 8489 1500, "
                      "write P100 FIELDBUS)");
            return EXIT_USAGE;
        }
    } else if (strcmp(pos[0], "im0") == 0) {
        run.op = OP_IM0;
        if (npos != 1) {
            cli_error("param: im0 takes no argument ('%s')", pos[1]);
            return EXIT_USAGE;
        }
        if (!via_given) {
            run.via = VIA_MOVILINK; /* class 1 */
        } else if (run.via == VIA_CHANNEL) {
            cli_error("param: im0 needs DP-V1: --via movilink, profidrive (class 1) or c2");
            return EXIT_USAGE;
        }
    } else {
        cli_error("param: unknown operation '%s' (read, write or im0)", pos[0]);
        return EXIT_USAGE;
    }
    run.n = run.op == OP_READ ? (uint8_t)(npos - 1) : 1u;
    for (unsigned i = 0; run.op != OP_IM0 && i < run.n; i++) {
        if (!parse_index(pos[1 + i], &run.index[i])) return EXIT_USAGE;
    }
    if (run.op == OP_WRITE && !parse_value(run.index[0], pos[2], &run.value)) return EXIT_USAGE;
    if (run.n > 1u && run.via == VIA_CHANNEL) {
        cli_error("param: the cyclic channel carries one service at a time; read several "
                  "indices with --via movilink, profidrive or c2 (one data set 47 request)");
        return EXIT_USAGE;
    }
    if (run.volatile_write && run.op != OP_WRITE) {
        cli_error("param: --volatile belongs to write");
        return EXIT_USAGE;
    }
    if (run.volatile_write && run.via != VIA_MOVILINK && run.via != VIA_CHANNEL) {
        cli_error("param: --volatile works with --via movilink or channel (PROFIdrive change "
                  "parameter always writes non-volatile)");
        return EXIT_USAGE;
    }
    if (!have_own) {
        own = run.via == VIA_C2 ? 1u : 2u;
    }
    if (own == address) {
        cli_error("param: --master-address %u is the slave's address", own);
        return EXIT_USAGE;
    }

    char err[256];
    if (tty_port_open(&port, dev, baud, err, sizeof err) != 0) {
        cli_error("%s", err);
        return 1;
    }
    static uint64_t t0;
    t0 = host_clock_mono_ns();
    rep.now_ns = clock_now;
    rep.now_ctx = &t0;
    {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        rep.capture_direction = true;
        if (!report_open_capture(&rep, &capture,
                                 (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec)) {
            tty_port_close(&port);
            return 1;
        }
    }
    cli_catch_stop_signals();

    dp_master_cfg_t mc = {.address = (uint8_t)own, .baud = baud, .strict_timing = false,
                          .slot_time_us = 100000u, .uart = tty_port_uart(&port),
                          .event = verbose ? report_master_event : quiet_event,
                          .event_ctx = &rep};
    dp_master_init(&run.master, &mc, tty_now_us());
    if (run.via != VIA_C2) {
        dpm_slave_cfg_t sc = {.address = (uint8_t)address};
        if (run.via == VIA_CHANNEL) {
            sc.prm_len = (uint8_t)dpm_build_prm(sc.prm, DFP21B_IDENT, 1000,
                                                dfp21b_user_prm_default,
                                                sizeof dfp21b_user_prm_default);
        } else {
            sc.prm_len = (uint8_t)dpm_build_prm_dpv1(sc.prm, DFP21B_IDENT, 1000,
                                                     dfp21b_user_prm_default,
                                                     sizeof dfp21b_user_prm_default);
        }
        memcpy(sc.cfg, cfg_param_3pd, sizeof cfg_param_3pd);
        sc.cfg_len = sizeof cfg_param_3pd;
        (void)dp_master_add_slave(&run.master, &sc);
    } else {
        dpm_c2_cfg_t cc = {.slave = (uint8_t)address, .address = (uint8_t)own};
        dpm_c2_init(&run.c2, &cc);
        (void)dp_master_add_c2(&run.master, &run.c2);
        (void)dpm_c2_open(&run.c2, c2_opened, NULL, tty_now_us());
    }
    tty_runner_init(&runner);
    tty_runner_set_tap(&runner, report_tap, &rep);
    sim_station_t st = master_station(&run.master);
    tty_runner_add(&runner, &port, &st);
    tty_runner_add_timer(&runner, master_timer, &run.master); /* so a new request goes at once */

    uint64_t end_ns = host_clock_mono_ns() + (uint64_t)timeout_s * 1000000000ull;
    const char *fail = NULL;
    while (run.stage != ST_DONE && !cli_stop && host_clock_mono_ns() < end_ns) {
        if (tty_runner_run_until(&runner, tty_now_us() + 5000u, &cli_stop) < 0) {
            fail = tty_runner_error(&runner);
            break;
        }
        step();
    }
    if (run.stage != ST_DONE) {
        if (fail != NULL) {
            set_result_error("failed", "%s", fail);
        } else if (cli_stop) {
            set_result_error("failed", "interrupted");
        } else {
            timeout_text(timeout_s);
        }
    }
    print_result();
    tty_port_close(&port);
    if (report_close_capture(&rep) != 0) {
        return 1;
    }
    return run.ok ? 0 : 1;
}
