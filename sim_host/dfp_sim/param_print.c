/* dfp-sim param's results: one line, or one JSON object, per parameter. See param_run.h. */
#include <stdio.h>
#include <string.h>

#include "movidrive/movidrive_names.h"
#include "param_run.h"

const char *const param_via_names[4] = {"channel", "movilink", "profidrive", "c2"};
static const char *const op_names[] = {"read", "write", "im0"};

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
            (void)putchar(ch);
        }
    }
    (void)putchar('"');
}

/* Copy without the blanks a fixed-width I&M text is padded with. */
static void trimmed(char *out, size_t max, const char *in)
{
    (void)snprintf(out, max, "%s", in);
    size_t n = strlen(out);
    while (n > 0u && (out[n - 1u] == ' ' || out[n - 1u] == '\0')) {
        out[--n] = '\0';
    }
}

/* The I&M0 texts as printed: order id and serial number without padding, "V1.2.3". */
typedef struct im0_texts {
    char order[24];
    char serial[20];
    char sw[24];
} im0_texts_t;

static void im0_texts(const dp_master_im0_t *im0, im0_texts_t *t)
{
    trimmed(t->order, sizeof t->order, im0->order_id);
    trimmed(t->serial, sizeof t->serial, im0->serial_number);
    (void)snprintf(t->sw, sizeof t->sw, "%c%u.%u.%u",
                   im0->sw_prefix != '\0' ? im0->sw_prefix : '?', im0->sw_major, im0->sw_minor,
                   im0->sw_bugfix);
}

/* "P100" and "setpoint source" for a table row, "H12" and "IPOS plus variable H12" for an IPOS
 * variable; false for an index the name table lacks. */
typedef struct param_name {
    const movidrive_param_info_t *info;
    char pnum[24];
    char name[64];
} param_name_t;

static bool param_names(uint16_t index, param_name_t *pn)
{
    pn->info = movidrive_param_info(index);
    if (pn->info != NULL) {
        (void)snprintf(pn->pnum, sizeof pn->pnum, "%s", pn->info->p_number);
        (void)snprintf(pn->name, sizeof pn->name, "%s", pn->info->name);
        return true;
    }
    if (index >= IPOS_FIRST && index < IPOS_FIRST + IPOS_COUNT) {
        (void)snprintf(pn->pnum, sizeof pn->pnum, "H%u", index - IPOS_FIRST);
        (void)snprintf(pn->name, sizeof pn->name, "IPOS plus variable H%u", index - IPOS_FIRST);
        return true;
    }
    return false;
}

/* "P100 setpoint source = 3 (FIELDBUS)", "P076 firmware basic unit = 823947913 (0x311C7289)",
 * "P160 internal setpoint n11 = 1.500 rpm (raw 1500, 0x000005DC)": the raw value stays in
 * sight wherever the text does not show it. */
static void value_line(const movidrive_param_info_t *info, uint32_t value, char *out, size_t n)
{
    char text[96];
    char raw[16];
    movidrive_value_text(info, (int32_t)value, text, sizeof text);
    (void)snprintf(raw, sizeof raw, "%d", (int32_t)value);
    if (info->num_enums > 0u) {
        (void)snprintf(out, n, "%s %s = %s", info->p_number, info->name, text);
    } else if (strcmp(text, raw) == 0) {
        (void)snprintf(out, n, "%s %s = %s (0x%08X)", info->p_number, info->name, text, value);
    } else {
        (void)snprintf(out, n, "%s %s = %s (raw %s, 0x%08X)", info->p_number, info->name, text,
                       raw, value);
    }
}

static void print_im0_json(const dp_master_im0_t *im0)
{
    im0_texts_t t;
    im0_texts(im0, &t);
    char hex[8];
    printf(",\"manufacturer_id\":%u", im0->manufacturer_id);
    (void)snprintf(hex, sizeof hex, "0x%04X", im0->manufacturer_id);
    json_str("manufacturer", hex);
    json_str("order_id", t.order);
    json_str("serial_number", t.serial);
    printf(",\"hardware_revision\":%u", im0->hardware_revision);
    json_str("software_revision", t.sw);
    printf(",\"rev_counter\":%u,\"profile_id\":%u,\"profile_specific_type\":%u",
           im0->rev_counter, im0->profile_id, im0->profile_specific_type);
    (void)snprintf(hex, sizeof hex, "%u.%u", im0->im_version_major, im0->im_version_minor);
    json_str("im_version", hex);
    (void)snprintf(hex, sizeof hex, "0x%04X", im0->im_supported);
    json_str("im_supported", hex);
}

static void print_json(const run_t *run, unsigned i, const param_name_t *pn, bool named)
{
    const param_result_t *r = &run->r[i];
    char vtext[96];
    printf("{\"op\":\"%s\"", op_names[run->op]);
    if (run->op != OP_IM0) {
        printf(",\"index\":%u", run->index[i]);
    }
    if (named) {
        json_str("p_number", pn->pnum);
        json_str("name", pn->name);
    }
    json_str("via", param_via_names[run->via]);
    if (run->op == OP_WRITE) {
        printf(",\"volatile\":%s,\"value\":%d", run->volatile_write ? "true" : "false",
               (int32_t)run->value);
        if (r->ok && named) {
            movidrive_value_text(pn->info, (int32_t)run->value, vtext, sizeof vtext);
            json_str("text", vtext);
        }
    }
    printf(",\"ok\":%s", r->ok ? "true" : "false");
    if (r->ok && r->have_value) {
        printf(",\"value\":%d,\"hex\":\"0x%08X\"", (int32_t)r->value, r->value);
        if (named && run->op == OP_READ) {
            movidrive_value_text(pn->info, (int32_t)r->value, vtext, sizeof vtext);
            json_str("text", vtext);
        }
    }
    if (r->ok && run->op == OP_IM0) {
        print_im0_json(&run->im0);
    }
    if (!r->ok) {
        json_str("error", r->error);
        json_str("text", r->text);
    }
    printf("}\n");
}

static void print_im0_text(const char *what, const dp_master_im0_t *im0)
{
    im0_texts_t t;
    im0_texts(im0, &t);
    printf("%s:\n"
           "  manufacturer id    0x%04X\n"
           "  order id           %s\n"
           "  serial number      %s\n"
           "  hardware revision  %u\n"
           "  software revision  %s\n"
           "  revision counter   %u\n"
           "  profile id         0x%04X (specific type 0x%04X)\n"
           "  I&M version        %u.%u, supported 0x%04X\n",
           what, im0->manufacturer_id, t.order, t.serial, im0->hardware_revision, t.sw,
           im0->rev_counter, im0->profile_id, im0->profile_specific_type, im0->im_version_major,
           im0->im_version_minor, im0->im_supported);
}

static void print_text(const run_t *run, unsigned i, const movidrive_param_info_t *info,
                       const char *what)
{
    const param_result_t *r = &run->r[i];
    char line[200];
    if (!r->ok) {
        printf("%s: error %s: %s\n", what, r->error, r->text);
    } else if (run->op == OP_IM0) {
        print_im0_text(what, &run->im0);
    } else if (r->have_value && info != NULL) {
        value_line(info, r->value, line, sizeof line);
        printf("%s: %s\n", what, line);
    } else if (r->have_value) {
        printf("%s: %d (0x%08X)\n", what, (int32_t)r->value, r->value);
    } else if (info != NULL) {
        value_line(info, run->value, line, sizeof line);
        printf("%s: ok (%s)\n", what, line);
    } else {
        printf("%s: ok\n", what);
    }
}

/* "read 8461 via channel", "write volatile 8489 = 1500 via movilink", "im0 via c2". */
static void describe(const run_t *run, unsigned i, char *what, size_t n)
{
    const char *via = param_via_names[run->via];
    if (run->op == OP_IM0) {
        (void)snprintf(what, n, "im0 via %s", via);
    } else if (run->op == OP_READ) {
        (void)snprintf(what, n, "read %u via %s", run->index[i], via);
    } else {
        (void)snprintf(what, n, "write%s %u = %d via %s", run->volatile_write ? " volatile" : "",
                       run->index[i], (int32_t)run->value, via);
    }
}

void param_print_results(const run_t *run)
{
    for (unsigned i = 0; i < run->n; i++) {
        param_name_t pn = {.info = NULL, .pnum = "", .name = ""};
        bool named = run->op != OP_IM0 && param_names(run->index[i], &pn);
        if (run->json) {
            print_json(run, i, &pn, named);
        } else {
            char what[64];
            describe(run, i, what, sizeof what);
            print_text(run, i, pn.info, what);
        }
    }
    (void)fflush(stdout);
}
