/* One logical line as a statement: sections, the keywords outside blocks (numbers, strings,
 * the rates, the global user parameters) and the openers of blocks (gsd_blocks.c). */
#include <stdio.h>
#include <string.h>

#include "gsd_internal.h"

char gsd_lower(char c)
{
    if (c < 'A' || c > 'Z') return c;
    return (char)(unsigned char)((unsigned char)c + ('a' - 'A'));
}

static char lower(char c)
{
    return gsd_lower(c);
}

bool gsd_same(const char *a, const char *b)
{
    while (*a != '\0' && lower(*a) == lower(*b)) {
        a++;
        b++;
    }
    return *a == '\0' && *b == '\0';
}

void gsd_skip_blanks(const char **s)
{
    while (**s == ' ' || **s == '\t') (*s)++;
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static int hex_digit(char c)
{
    if (is_digit(c)) return c - '0';
    c = lower(c);
    return (c >= 'a' && c <= 'f') ? c - 'a' + 10 : -1;
}

static bool is_word_char(char c)
{
    return is_digit(c) || (lower(c) >= 'a' && lower(c) <= 'z') || c == '_' || c == '.';
}

/* Decimal or 0x hex, optionally negative. A number too large for any GSD field saturates at
 * 2^40, so the caller's range check words the error. */
bool gsd_read_int(const char **s, int64_t *v)
{
    const char *q = *s;
    bool neg = *q == '-';
    if (neg) q++;
    const uint64_t cap = (uint64_t)1 << 40;
    uint64_t acc = 0;
    int digits = 0;
    if (q[0] == '0' && (q[1] == 'x' || q[1] == 'X') && hex_digit(q[2]) >= 0) {
        for (q += 2; hex_digit(*q) >= 0; q++, digits++) {
            acc = acc >= cap ? cap : acc * 16u + (uint64_t)hex_digit(*q);
        }
    } else {
        for (; is_digit(*q); q++, digits++) {
            acc = acc >= cap ? cap : acc * 10u + (uint64_t)(*q - '0');
        }
    }
    if (digits == 0 || is_word_char(*q)) return false;
    *v = neg ? -(int64_t)acc : (int64_t)acc;
    *s = q;
    gsd_skip_blanks(s);
    return true;
}

/* --- keywords kept as numbers ------------------------------------------------------------ */

typedef enum num_kind { KV_BOOL, KV_U8, KV_U16, KV_FAMILY } num_kind_t;

typedef struct num_keyword {
    const char *name;
    gsd_key_t key;
    num_kind_t kind;
} num_keyword_t;

static const num_keyword_t num_keywords[] = {
    {"GSD_Revision", GSD_K_GSD_REVISION, KV_U8},
    {"Ident_Number", GSD_K_IDENT_NUMBER, KV_U16},
    {"Protocol_Ident", GSD_K_PROTOCOL_IDENT, KV_U8},
    {"Station_Type", GSD_K_STATION_TYPE, KV_U8},
    {"FMS_supp", GSD_K_FMS_SUPP, KV_BOOL},
    {"Revision_Number", GSD_K_REVISION_NUMBER, KV_U8},
    {"Repeater_Ctrl_Sig", GSD_K_REPEATER_CTRL_SIG, KV_U8},
    {"24V_Pins", GSD_K_24V_PINS, KV_U8},
    {"Auto_Baud_supp", GSD_K_AUTO_BAUD_SUPP, KV_BOOL},
    {"Set_Slave_Add_supp", GSD_K_SET_SLAVE_ADD_SUPP, KV_BOOL},
    {"Freeze_Mode_supp", GSD_K_FREEZE_MODE_SUPP, KV_BOOL},
    {"Sync_Mode_supp", GSD_K_SYNC_MODE_SUPP, KV_BOOL},
    {"Fail_Safe", GSD_K_FAIL_SAFE, KV_BOOL},
    {"Min_Slave_Intervall", GSD_K_MIN_SLAVE_INTERVALL, KV_U16},
    {"Slave_Family", GSD_K_SLAVE_FAMILY, KV_FAMILY},
    {"Modular_Station", GSD_K_MODULAR_STATION, KV_BOOL},
    {"Max_Module", GSD_K_MAX_MODULE, KV_U8},
    {"Max_Input_Len", GSD_K_MAX_INPUT_LEN, KV_U8},
    {"Max_Output_Len", GSD_K_MAX_OUTPUT_LEN, KV_U8},
    {"Max_Data_Len", GSD_K_MAX_DATA_LEN, KV_U16},
    {"Modul_Offset", GSD_K_MODUL_OFFSET, KV_U8},
    {"Max_Diag_Data_Len", GSD_K_MAX_DIAG_DATA_LEN, KV_U8},
    {"User_Prm_Data_Len", GSD_K_USER_PRM_DATA_LEN, KV_U8},
    {"Max_User_Prm_Data_Len", GSD_K_MAX_USER_PRM_DATA_LEN, KV_U8},
    {"Prm_Block_Structure_supp", GSD_K_PRM_BLOCK_STRUCTURE_SUPP, KV_BOOL},
    {"Ident_Maintenance_supp", GSD_K_IDENT_MAINTENANCE_SUPP, KV_BOOL},
    {"DPV1_Slave", GSD_K_DPV1_SLAVE, KV_BOOL},
    {"C1_Read_Write_supp", GSD_K_C1_READ_WRITE_SUPP, KV_BOOL},
    {"C1_Max_Data_Len", GSD_K_C1_MAX_DATA_LEN, KV_U8},
    {"C1_Response_Timeout", GSD_K_C1_RESPONSE_TIMEOUT, KV_U16},
    {"C1_Read_Write_required", GSD_K_C1_READ_WRITE_REQUIRED, KV_BOOL},
    {"C2_Read_Write_supp", GSD_K_C2_READ_WRITE_SUPP, KV_BOOL},
    {"C2_Max_Data_Len", GSD_K_C2_MAX_DATA_LEN, KV_U8},
    {"C2_Response_Timeout", GSD_K_C2_RESPONSE_TIMEOUT, KV_U16},
    {"C2_Read_Write_required", GSD_K_C2_READ_WRITE_REQUIRED, KV_BOOL},
    {"C2_Max_Count_Channels", GSD_K_C2_MAX_COUNT_CHANNELS, KV_U8},
    {"Max_Initiate_PDU_Length", GSD_K_MAX_INITIATE_PDU_LENGTH, KV_U8},
    {"DPV1_Data_Types", GSD_K_DPV1_DATA_TYPES, KV_BOOL},
    {"WD_Base_1ms_supp", GSD_K_WD_BASE_1MS_SUPP, KV_BOOL},
    {"Check_Cfg_Mode", GSD_K_CHECK_CFG_MODE, KV_BOOL},
    {"Diagnostic_Alarm_supp", GSD_K_DIAGNOSTIC_ALARM_SUPP, KV_BOOL},
    {"Process_Alarm_supp", GSD_K_PROCESS_ALARM_SUPP, KV_BOOL},
    {"Pull_Plug_Alarm_supp", GSD_K_PULL_PLUG_ALARM_SUPP, KV_BOOL},
    {"Status_Alarm_supp", GSD_K_STATUS_ALARM_SUPP, KV_BOOL},
    {"Update_Alarm_supp", GSD_K_UPDATE_ALARM_SUPP, KV_BOOL},
    {"Manufacturer_Specific_Alarm_supp", GSD_K_MANUFACTURER_SPECIFIC_ALARM_SUPP, KV_BOOL},
    {"Extra_Alarm_SAP_supp", GSD_K_EXTRA_ALARM_SAP_SUPP, KV_BOOL},
    {"Alarm_Sequence_Mode_Count", GSD_K_ALARM_SEQUENCE_MODE_COUNT, KV_U8},
    {"Alarm_Type_Mode_supp", GSD_K_ALARM_TYPE_MODE_SUPP, KV_BOOL},
    {"Diagnostic_Alarm_required", GSD_K_DIAGNOSTIC_ALARM_REQUIRED, KV_BOOL},
    {"Process_Alarm_required", GSD_K_PROCESS_ALARM_REQUIRED, KV_BOOL},
    {"Pull_Plug_Alarm_required", GSD_K_PULL_PLUG_ALARM_REQUIRED, KV_BOOL},
    {"Status_Alarm_required", GSD_K_STATUS_ALARM_REQUIRED, KV_BOOL},
    {"Update_Alarm_required", GSD_K_UPDATE_ALARM_REQUIRED, KV_BOOL},
    {"Manufacturer_Specific_Alarm_required", GSD_K_MANUFACTURER_SPECIFIC_ALARM_REQUIRED,
     KV_BOOL},
};

static const struct {
    const char *name;
    gsd_str_key_t key;
} str_keywords[] = {
    {"Vendor_Name", GSD_S_VENDOR_NAME},
    {"Model_Name", GSD_S_MODEL_NAME},
    {"Revision", GSD_S_REVISION},
    {"Hardware_Release", GSD_S_HARDWARE_RELEASE},
    {"Software_Release", GSD_S_SOFTWARE_RELEASE},
    {"OrderNumber", GSD_S_ORDER_NUMBER},
    {"Implementation_Type", GSD_S_IMPLEMENTATION_TYPE},
};

const char *gsd_key_name(gsd_key_t k)
{
    for (size_t i = 0; i < sizeof num_keywords / sizeof num_keywords[0]; i++) {
        if (num_keywords[i].key == k) return num_keywords[i].name;
    }
    return "?";
}

void gsd_note(gsd_parser_t *p, gsd_note_kind_t kind, const char *kw, uint32_t line,
              uint32_t first_line)
{
    gsd_t *g = p->g;
    g->notes_total++;
    if (g->n_notes == GSD_MAX_NOTES) return;
    gsd_note_t *n = &g->notes[g->n_notes++];
    n->kind = kind;
    n->line = line;
    n->first_line = first_line;
    (void)snprintf(n->keyword, sizeof n->keyword, "%s", kw);
}

bool gsd_expect_end(gsd_parser_t *p, const gsd_stmt_t *st, const char *s)
{
    if (*s == '\0') return true;
    return gsd_fail(p, st->line, "%s: unexpected '%.24s' after the value", st->kw, s);
}

bool gsd_read_number(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, int64_t lo,
                     int64_t hi, int64_t *v)
{
    if (!gsd_read_int(s, v)) {
        return gsd_fail(p, st->line, "%s: expected a number, found '%.24s'", st->kw, *s);
    }
    if (*v < lo || *v > hi) {
        return gsd_fail(p, st->line, "%s: %lld is out of range %lld..%lld", st->kw,
                        (long long)*v, (long long)lo, (long long)hi);
    }
    return true;
}

/* Keyword = number, alone: its value in lo..hi. */
bool gsd_plain_number(gsd_parser_t *p, const gsd_stmt_t *st, int64_t lo, int64_t hi,
                      int64_t *v)
{
    if (!st->eq) return gsd_fail(p, st->line, "%s needs '= value'", st->kw);
    const char *s = st->val;
    return gsd_read_number(p, st, &s, lo, hi, v) && gsd_expect_end(p, st, s);
}

static bool number_keyword(gsd_parser_t *p, const gsd_stmt_t *st, const num_keyword_t *k)
{
    static const int64_t hi[] = {[KV_BOOL] = 1, [KV_U8] = 255, [KV_U16] = 65535,
                                 [KV_FAMILY] = 255};
    if (!st->eq) return gsd_fail(p, st->line, "%s needs '= value'", st->kw);
    const char *s = st->val;
    int64_t v = 0;
    if (!gsd_read_number(p, st, &s, 0, hi[k->kind], &v)) return false;
    /* Slave_Family = 1@TdF@... : the sub-families after '@' are for configurators' menus */
    if (!(k->kind == KV_FAMILY && *s == '@') && !gsd_expect_end(p, st, s)) return false;
    gsd_t *g = p->g;
    if (g->key_line[k->key] != 0u) {
        gsd_note(p, GSD_NOTE_REPEATED, k->name, st->line, g->key_line[k->key]);
    }
    g->key[k->key] = (uint32_t)v;
    g->key_line[k->key] = st->line;
    return true;
}

bool gsd_store_string(gsd_parser_t *p, uint32_t line, const char *s, size_t len, uint32_t *off)
{
    gsd_t *g = p->g;
    if (len > GSD_MAX_STRING) {
        return gsd_fail(p, line, "a string longer than %u characters", GSD_MAX_STRING);
    }
    if (g->n_chars + len + 1u > GSD_MAX_CHARS) {
        return gsd_fail(p, line, "the strings exceed %u characters together (GSD_MAX_CHARS)",
                        GSD_MAX_CHARS);
    }
    *off = (uint32_t)g->n_chars;
    memcpy(g->chars + g->n_chars, s, len);
    g->chars[g->n_chars + len] = '\0';
    g->n_chars += len + 1u;
    return true;
}

bool gsd_read_string(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, uint32_t *off)
{
    if (**s != '"') {
        return gsd_fail(p, st->line, "%s: expected a \"string\", found '%.24s'", st->kw, *s);
    }
    const char *start = *s + 1;
    const char *end = strchr(start, '"');
    if (end == NULL) return gsd_fail(p, st->line, "%s: a string without its closing '\"'",
                                     st->kw);
    if (!gsd_store_string(p, st->line, start, (size_t)(end - start), off)) return false;
    *s = end + 1;
    gsd_skip_blanks(s);
    return true;
}

static bool string_keyword(gsd_parser_t *p, const gsd_stmt_t *st, gsd_str_key_t k)
{
    if (!st->eq) return gsd_fail(p, st->line, "%s needs '= value'", st->kw);
    const char *s = st->val;
    uint32_t off = 0;
    if (!gsd_read_string(p, st, &s, &off) || !gsd_expect_end(p, st, s)) return false;
    gsd_t *g = p->g;
    if (g->str_line[k] != 0u) gsd_note(p, GSD_NOTE_REPEATED, st->kw, st->line, g->str_line[k]);
    g->str[k] = off;
    g->str_line[k] = st->line;
    return true;
}

/* <rate>_supp and MaxTsdr_<rate>: NOT_MINE for any other keyword. */
static gsd_outcome_t rate_keyword(gsd_parser_t *p, const gsd_stmt_t *st)
{
    static const char tsdr_prefix[] = "MaxTsdr_";
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        char name[32];
        gsd_rate_t *r = &p->g->rate[i];
        bool supp = false;
        (void)snprintf(name, sizeof name, "%s_supp", gsd_rate_name(i));
        if (gsd_same(st->kw, name)) {
            supp = true;
        } else {
            (void)snprintf(name, sizeof name, "%s%s", tsdr_prefix, gsd_rate_name(i));
            if (!gsd_same(st->kw, name)) continue;
        }
        int64_t v = 0;
        if (!gsd_plain_number(p, st, 0, supp ? 1 : 65535, &v)) return GSD_FAILED;
        uint32_t *line = supp ? &r->supp_line : &r->tsdr_line;
        if (*line != 0u) gsd_note(p, GSD_NOTE_REPEATED, st->kw, st->line, *line);
        *line = st->line;
        if (supp) {
            r->supp = v != 0;
        } else {
            r->max_tsdr = (uint16_t)v;
        }
        return GSD_DONE;
    }
    return GSD_NOT_MINE;
}

static gsd_outcome_t simple_keyword(gsd_parser_t *p, const gsd_stmt_t *st)
{
    for (size_t i = 0; i < sizeof num_keywords / sizeof num_keywords[0]; i++) {
        if (gsd_same(st->kw, num_keywords[i].name)) {
            return number_keyword(p, st, &num_keywords[i]) ? GSD_DONE : GSD_FAILED;
        }
    }
    for (size_t i = 0; i < sizeof str_keywords / sizeof str_keywords[0]; i++) {
        if (gsd_same(st->kw, str_keywords[i].name)) {
            return string_keyword(p, st, str_keywords[i].key) ? GSD_DONE : GSD_FAILED;
        }
    }
    return rate_keyword(p, st);
}

/* User_Prm_Data = octets: the revision 1 form of the whole global part at once. */
static bool user_prm_data(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    uint8_t octets[GSD_MAX_USER_PRM];
    size_t n = 0;
    if (!st->eq) return gsd_fail(p, st->line, "%s needs '= value'", st->kw);
    const char *s = st->val;
    int r = gsd_read_octets(p, st, &s, octets, sizeof octets, &n);
    if (r < 0) {
        return gsd_fail(p, st->line, "User_Prm_Data: more than %u octets", GSD_MAX_USER_PRM);
    }
    if (r == 0 || !gsd_expect_end(p, st, s)) return false;
    if (g->user_prm_data_line != 0u) {
        gsd_note(p, GSD_NOTE_REPEATED, st->kw, st->line, g->user_prm_data_line);
    }
    g->user_prm_data_line = st->line;
    memcpy(g->user_prm, octets, n);
    if (n > g->user_prm_written) g->user_prm_written = (uint16_t)n;
    return true;
}

static bool global_statement(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_outcome_t o = simple_keyword(p, st);
    if (o == GSD_NOT_MINE) o = gsd_prm_keyword(p, st, GSD_GLOBAL);
    if (o == GSD_NOT_MINE) o = gsd_block_opener(p, st);
    if (o != GSD_NOT_MINE) return o == GSD_DONE;
    if (gsd_same(st->kw, "User_Prm_Data")) return user_prm_data(p, st);
    if (is_digit(st->kw[0]) && !st->eq && st->arg == NULL && st->val[0] == '\0') {
        return gsd_fail(p, st->line, "a number where a keyword belongs ('%s')", st->kw);
    }
    gsd_note(p, GSD_NOTE_IGNORED, st->kw, st->line, 0u);
    return true;
}

/* Keyword [ (arg) ] [ = ] rest. */
static bool split(gsd_parser_t *p, const char *text, uint32_t line, gsd_stmt_t *st)
{
    const char *s = text;
    size_t k = 0;
    memset(st, 0, sizeof *st);
    st->line = line;
    while (is_word_char(*s)) {
        if (k + 1u >= sizeof st->kw) {
            return gsd_fail(p, line, "a keyword longer than %zu characters", sizeof st->kw - 1u);
        }
        st->kw[k++] = *s++;
    }
    if (k == 0u) return gsd_fail(p, line, "expected a keyword, found '%.24s'", text);
    gsd_skip_blanks(&s);
    if (*s == '(') {
        st->arg = ++s;
        const char *close = strchr(s, ')');
        if (close == NULL) return gsd_fail(p, line, "%s: '(' without ')'", st->kw);
        st->arg_len = (size_t)(close - s);
        s = close + 1;
        gsd_skip_blanks(&s);
    }
    if (*s == '=') {
        st->eq = true;
        s++;
        gsd_skip_blanks(&s);
    }
    st->val = s;
    return true;
}

static bool section(gsd_parser_t *p, const char *text, uint32_t line)
{
    if (gsd_same(text, "#Profibus_DP")) {
        if (p->st != GSD_ST_BEFORE) {
            return gsd_fail(p, line, "a second #Profibus_DP (the first is on line %u)",
                            (unsigned)p->g->header_line);
        }
        p->st = GSD_ST_GLOBAL;
        p->g->header_line = line;
        return true;
    }
    if (p->st == GSD_ST_BEFORE || p->st == GSD_ST_AFTER) return true;
    if (!gsd_finish(p)) return false;
    p->st = GSD_ST_AFTER;
    return true;
}

bool gsd_statement(gsd_parser_t *p, char *text, uint32_t line)
{
    if (text[0] == '#') return section(p, text, line);
    if (p->st == GSD_ST_AFTER) return true;
    if (p->st == GSD_ST_BEFORE) {
        return gsd_fail(p, line, "'%.24s' before the #Profibus_DP line", text);
    }
    gsd_stmt_t st;
    if (!split(p, text, line, &st)) return false;
    switch (p->st) {
    case GSD_ST_MODULE:
        return gsd_module_statement(p, &st);
    case GSD_ST_PRMTEXT:
        return gsd_prmtext_statement(p, &st);
    case GSD_ST_EXTPRM:
        return gsd_extprm_statement(p, &st);
    default:
        return global_statement(p, &st);
    }
}
