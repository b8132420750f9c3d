#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "http_internal.h"

enum MHD_Result http_submit(http_server_t *srv, struct MHD_Connection *conn, rig_cmd_t *cmd,
                            unsigned timeout_ms)
{
    rig_ctl_submit(srv->ctl, cmd, timeout_ms);
    if (cmd->status != 200) {
        return http_send_error(conn, (unsigned)cmd->status, "%s", cmd->error);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "ok", true);
    return http_send_json(conn, 200, o);
}

static enum MHD_Result param_answer(http_server_t *srv, struct MHD_Connection *conn, rig_cmd_t *cmd,
                                    const movidrive_param_info_t *p, unsigned timeout)
{
    rig_ctl_submit(srv->ctl, cmd, timeout);
    if (cmd->status != 200) {
        return http_send_error(conn, (unsigned)cmd->status, "%s", cmd->error);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "ok", !cmd->refused);
    cJSON_AddStringToObject(o, "p_number", p->p_number);
    cJSON_AddNumberToObject(o, "index", p->index);
    cJSON_AddStringToObject(o, "name", p->name);
    if (cmd->refused) {
        char msg[240];
        (void)snprintf(msg, sizeof msg, "MOVILINK error: %s", cmd->error);
        cJSON_AddStringToObject(o, "error", msg);
    } else {
        char text[128];
        movidrive_value_text(p, cmd->result, text, sizeof text);
        cJSON_AddNumberToObject(o, "value", cmd->result);
        cJSON_AddStringToObject(o, "text", text);
    }
    unsigned status = cmd->refused && !(cmd->type == RIG_CMD_MASTER_PARAM) ? 400u : 200u;
    return http_send_json(conn, status, o);
}

enum MHD_Result http_card_action(http_server_t *srv, struct MHD_Connection *conn,
                                 uint8_t address, const char *what, const request_t *req)
{
    enum MHD_Result rc = MHD_NO;
    char err[200] = "";
    rig_cmd_t cmd = {.card = address};
    cJSON *o = NULL;
    if (strcmp(what, "inputs") == 0) {
        static const char *const allowed[] = {"DI00", NULL};
        if ((o = http_parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_INPUTS;
        if (!http_get_bool(o, "DI00", true, &cmd.flag, err, sizeof err)) goto bad;
    } else if (strcmp(what, "fault") == 0) {
        static const char *const allowed[] = {"fault", NULL};
        if ((o = http_parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        long v = 0;
        cmd.type = RIG_CMD_FAULT;
        if (!http_get_int(o, "fault", true, 1, 255, &v, err, sizeof err)) goto bad;
        cmd.value = (int32_t)v;
    } else if (strcmp(what, "cable") == 0) {
        static const char *const allowed[] = {"connected", NULL};
        if ((o = http_parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_CABLE;
        if (!http_get_bool(o, "connected", true, &cmd.flag, err, sizeof err)) goto bad;
    } else if (strcmp(what, "power-cycle") == 0) {
        static const char *const allowed[] = {NULL};
        if ((o = http_parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_POWER_CYCLE;
    } else if (strcmp(what, "dip") == 0) {
        static const char *const allowed[] = {"address", NULL};
        if ((o = http_parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        long v = 0;
        cmd.type = RIG_CMD_DIP;
        if (!http_get_int(o, "address", true, 0, 127, &v, err, sizeof err)) goto bad;
        cmd.value = (int32_t)v;
    } else {
        return http_send_error(conn, 404, "no action '%s' for a card", what);
    }
    cJSON_Delete(o);
    return http_submit(srv, conn, &cmd, ACTION_TIMEOUT_MS);
bad:
    cJSON_Delete(o);
    return http_send_error(conn, 400, "%s", err);
}

enum MHD_Result http_card_param(http_server_t *srv, struct MHD_Connection *conn,
                                uint8_t address, const char *name, const char *method,
                                const request_t *req)
{
    char err[300];
    const movidrive_param_info_t *p = movidrive_param_find(name, err, sizeof err);
    if (p == NULL) {
        return http_send_error(conn, 404, "%s", err);
    }
    rig_cmd_t cmd = {.card = address, .index = p->index, .type = RIG_CMD_PARAM_READ};
    if (strcmp(method, "PUT") == 0) {
        static const char *const allowed[] = {"value", "volatile", NULL};
        enum MHD_Result rc = MHD_NO;
        cJSON *o = http_parse_body(conn, req, allowed, &rc);
        if (o == NULL) {
            return rc;
        }
        cmd.type = RIG_CMD_PARAM_WRITE;
        bool ok = http_get_value(o, p, &cmd.value, err, sizeof err) &&
                  http_get_bool(o, "volatile", false, &cmd.flag, err, sizeof err);
        cJSON_Delete(o);
        if (!ok) {
            return http_send_error(conn, 400, "%s", err);
        }
    }
    return param_answer(srv, conn, &cmd, p, ACTION_TIMEOUT_MS);
}

enum MHD_Result http_master_run(http_server_t *srv, struct MHD_Connection *conn,
                                const request_t *req)
{
    static const char *const allowed[] = {"running", NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *o = http_parse_body(conn, req, allowed, &rc);
    if (o == NULL) {
        return rc;
    }
    char err[120] = "";
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_RUN};
    bool ok = http_get_bool(o, "running", true, &cmd.flag, err, sizeof err);
    cJSON_Delete(o);
    return ok ? http_submit(srv, conn, &cmd, ACTION_TIMEOUT_MS)
              : http_send_error(conn, 400, "%s", err);
}

/* "param": "P100", 8461 or a name. */
static const movidrive_param_info_t *param_named(const cJSON *param, char *err, size_t n)
{
    if (param != NULL && cJSON_IsNumber(param)) {
        /* Not valueint: cJSON truncates 8461.9 to 8461 and saturates 1e20 at INT_MAX. */
        double d = cJSON_GetNumberValue(param);
        if (!(d >= 0.0 && d <= 65535.0) || d != (double)(long)d) {
            (void)snprintf(err, n, "'param' must be an index 0..65535 (an integer such as 8461), "
                                   "\"P100\" or a name");
            return NULL;
        }
        char num[24];
        (void)snprintf(num, sizeof num, "%ld", (long)d);
        return movidrive_param_find(num, err, n);
    }
    if (param != NULL && cJSON_IsString(param)) {
        return movidrive_param_find(param->valuestring, err, n);
    }
    (void)snprintf(err, n, "'param' is required: \"P100\", 8461 or a name");
    return NULL;
}

/* "via": the path of a master parameter service (docs/api.md); absent is the channel. */
static bool via_named(const cJSON *via, rig_param_via_t *out, char *err, size_t n)
{
    static const struct {
        const char *name;
        rig_param_via_t via;
    } paths[] = {{"channel", RIG_VIA_CHANNEL}, {"ds47", RIG_VIA_DS47}, {"c2", RIG_VIA_C2}};
    if (via == NULL) {
        *out = RIG_VIA_CHANNEL;
        return true;
    }
    for (size_t i = 0; cJSON_IsString(via) && i < sizeof paths / sizeof paths[0]; i++) {
        if (strcmp(via->valuestring, paths[i].name) == 0) {
            *out = paths[i].via;
            return true;
        }
    }
    (void)snprintf(err, n, "'via' must be \"channel\", \"ds47\" or \"c2\"");
    return false;
}

/* The body of POST /api/v1/master/param into cmd; NULL with a message in err. */
static const movidrive_param_info_t *master_param_cmd(const cJSON *o, rig_cmd_t *cmd, char *err,
                                               size_t n)
{
    long slave = 0;
    const cJSON *op = cJSON_GetObjectItemCaseSensitive(o, "op");
    if (!http_get_int(o, "slave", true, 0, 125, &slave, err, n)) {
        return NULL;
    }
    cmd->card = (uint8_t)slave;
    if (!cJSON_IsString(op) ||
        (strcmp(op->valuestring, "read") != 0 && strcmp(op->valuestring, "write") != 0)) {
        (void)snprintf(err, n, "'op' must be \"read\" or \"write\"");
        return NULL;
    }
    cmd->write = strcmp(op->valuestring, "write") == 0;
    const movidrive_param_info_t *p =
        param_named(cJSON_GetObjectItemCaseSensitive(o, "param"), err, n);
    if (p == NULL) {
        return NULL;
    }
    cmd->index = p->index;
    if (!via_named(cJSON_GetObjectItemCaseSensitive(o, "via"), &cmd->via, err, n)) {
        return NULL;
    }
    if (cmd->write && !http_get_value(o, p, &cmd->value, err, n)) {
        return NULL;
    }
    if (!cmd->write && cJSON_GetObjectItemCaseSensitive(o, "value") != NULL) {
        (void)snprintf(err, n, "'value' belongs to \"op\": \"write\"");
        return NULL;
    }
    if (!http_get_bool(o, "volatile", false, &cmd->flag, err, n)) {
        return NULL;
    }
    return p;
}

enum MHD_Result http_master_param(http_server_t *srv, struct MHD_Connection *conn,
                                  const request_t *req)
{
    static const char *const allowed[] = {"slave", "op", "param", "value", "via", "volatile",
                                          NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *o = http_parse_body(conn, req, allowed, &rc);
    if (o == NULL) {
        return rc;
    }
    char err[300] = "";
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_PARAM};
    const movidrive_param_info_t *p = master_param_cmd(o, &cmd, err, sizeof err);
    cJSON_Delete(o);
    if (p == NULL) {
        return http_send_error(conn, 400, "%s", err);
    }
    return param_answer(srv, conn, &cmd, p, SERVICE_TIMEOUT_MS);
}

/* "po": a list of words from the first PO word on. */
static bool po_words(const cJSON *po, rig_cmd_t *cmd, char *err, size_t n)
{
    int count = cJSON_GetArraySize(po);
    if (!cJSON_IsArray(po) || count < 1 || count > (int)DFP21B_MAX_PD) {
        (void)snprintf(err, n, "'po' must be a list of 1..%u words", DFP21B_MAX_PD);
        return false;
    }
    for (int i = 0; i < count; i++) {
        const cJSON *w = cJSON_GetArrayItem(po, i);
        double d = cJSON_GetNumberValue(w);
        if (!cJSON_IsNumber(w) || !(d >= -32768.0 && d <= 65535.0) || d != (double)(long)d) {
            (void)snprintf(err, n, "'po'[%d] must be a word 0..65535 (or -32768..-1)", i);
            return false;
        }
        cmd->words[i] = (uint16_t)(long)d;
    }
    cmd->num_words = (uint8_t)count;
    return true;
}

/* "hex": the whole output image. */
static bool hex_image(const cJSON *hex, rig_cmd_t *cmd, char *err, size_t n)
{
    const char *t = cJSON_GetStringValue(hex);
    size_t len = t != NULL ? strlen(t) : 0u;
    if (t == NULL || len % 2u != 0u || len / 2u > sizeof cmd->raw) {
        (void)snprintf(err, n, "'hex' must be an even number of hex digits (at most %zu octets)",
                       sizeof cmd->raw);
        return false;
    }
    for (size_t i = 0; i < len; i += 2u) {
        char pair[3] = {t[i], t[i + 1u], 0};
        if (strspn(pair, "0123456789abcdefABCDEF") != 2u) {
            (void)snprintf(err, n, "'hex': '%s' is not a hex octet", pair);
            return false;
        }
        cmd->raw[i / 2u] = (uint8_t)strtoul(pair, NULL, 16);
    }
    cmd->raw_len = (uint8_t)(len / 2u);
    cmd->raw_given = true;
    return true;
}

enum MHD_Result http_master_outputs(http_server_t *srv, struct MHD_Connection *conn,
                                    uint8_t address, const request_t *req)
{
    static const char *const allowed[] = {"po", "hex", NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *o = http_parse_body(conn, req, allowed, &rc);
    if (o == NULL) {
        return rc;
    }
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_OUTPUTS, .card = address};
    const cJSON *po = cJSON_GetObjectItemCaseSensitive(o, "po");
    const cJSON *hex = cJSON_GetObjectItemCaseSensitive(o, "hex");
    char err[200] = "";
    bool ok;
    if ((po == NULL) == (hex == NULL)) {
        (void)snprintf(err, sizeof err, "give either 'po' (a list of words) or 'hex'");
        ok = false;
    } else if (po != NULL) {
        ok = po_words(po, &cmd, err, sizeof err);
    } else {
        ok = hex_image(hex, &cmd, err, sizeof err);
    }
    cJSON_Delete(o);
    if (!ok) {
        return http_send_error(conn, 400, "%s", err);
    }
    return http_submit(srv, conn, &cmd, ACTION_TIMEOUT_MS);
}
