/* The project's own GSD files (firmware/gsd) read by sim_host/gsd: exact values (ident, rates
 * and MaxTsdr, modules and their octets, the user parameter definition and defaults, the DP-V1
 * keys, the lines they are on), and both consistent.
 *
 * usage: test_gsd_files GSD_DIR */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gsd/gsd.h"

static gsd_t g; /* too large for a test's stack frame to be comfortable */
static const char *dir;

static bool load(const char *name)
{
    char path[512], err[GSD_ERR_LEN + 512];
    (void)snprintf(path, sizeof path, "%s/%s", dir, name);
    int rc = gsd_parse_file(path, &g, err, sizeof err);
    if (rc != 0) fprintf(stderr, "%s\n", err);
    CHECK_EQ(rc, 0);
    return rc == 0;
}

static const uint32_t bauds[GSD_RATE_COUNT] = {9600,   19200,   45450,   93750,   187500,
                                               500000, 1500000, 3000000, 6000000, 12000000};
static const uint32_t tsdr[GSD_RATE_COUNT] = {15, 15, 15, 15, 15, 32, 96, 192, 383, 0};

/* What both files say alike: the card is the same, only DP-V1 differs. */
static void common(size_t header_line)
{
    uint32_t v = 0;
    CHECK(gsd_key(&g, GSD_K_IDENT_NUMBER, &v));
    CHECK_EQ(v, 0x6003);
    CHECK_EQ(g.header_line, header_line);
    CHECK_EQ(g.key_line[GSD_K_IDENT_NUMBER], header_line + 5u);
    CHECK_STR(gsd_text(&g, GSD_S_VENDOR_NAME), "SEW-EURODRIVE");
    CHECK_STR(gsd_text(&g, GSD_S_REVISION), "DFP21B");
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        CHECK_EQ(gsd_supports_baud(&g, bauds[i]), i < 9u);
        CHECK_EQ(gsd_max_tsdr_bits(&g, bauds[i]), tsdr[i]);
        CHECK(g.rate[i].supp_line != 0u);
    }
    CHECK_EQ(g.rate[9].tsdr_line, 0);
    CHECK_EQ(gsd_max_tsdr_bits(&g, 57600), 0); /* no PROFIBUS rate */
    CHECK(!gsd_supports_baud(&g, 57600));
    CHECK(gsd_key(&g, GSD_K_MAX_INPUT_LEN, &v) && v == 28u);
    CHECK(gsd_key(&g, GSD_K_MAX_OUTPUT_LEN, &v) && v == 28u);
    CHECK(gsd_key(&g, GSD_K_MAX_DATA_LEN, &v) && v == 56u);
    CHECK(gsd_key(&g, GSD_K_MAX_DIAG_DATA_LEN, &v) && v == 8u);
    CHECK(gsd_key(&g, GSD_K_MAX_MODULE, &v) && v == 1u);
    CHECK(gsd_key(&g, GSD_K_USER_PRM_DATA_LEN, &v) && v == 9u);
    CHECK(gsd_key(&g, GSD_K_SLAVE_FAMILY, &v) && v == 1u);
    CHECK_EQ(g.n_notes, 0);
}

static void modules(void)
{
    uint16_t in = 0, out = 0;
    CHECK_EQ(g.n_modules, 20);
    CHECK_STR(gsd_chars(&g, g.modules[0].name), "1 PD");
    CHECK_BYTES(gsd_module_cfg(&g, 0), g.modules[0].cfg_len, 0xF0);
    CHECK(gsd_module_io(&g, 0, &in, &out));
    CHECK_EQ(in, 2);
    CHECK_EQ(out, 2);
    CHECK_STR(gsd_chars(&g, g.modules[3].name), "6 PD");
    CHECK_BYTES(gsd_module_cfg(&g, 3), g.modules[3].cfg_len, 0x00, 0xF5);
    CHECK_STR(gsd_chars(&g, g.modules[9].name), "Param + 10 PD");
    CHECK_BYTES(gsd_module_cfg(&g, 9), g.modules[9].cfg_len, 0xF3, 0xF9);
    CHECK(gsd_module_io(&g, 9, &in, &out));
    CHECK_EQ(in, 28);
    CHECK_EQ(out, 28);
    CHECK_STR(gsd_chars(&g, g.modules[19].name), "Param + 9 PD");
    CHECK_BYTES(gsd_module_cfg(&g, 19), g.modules[19].cfg_len, 0xF3, 0xF8);
    CHECK_EQ(gsd_find_module(&g, "Param + 3 PD"), 7);
    CHECK_EQ(gsd_find_module(&g, "param + 3 pd"), 7);
    CHECK_EQ(gsd_find_module(&g, "Param + 11 PD"), -1);
    for (size_t i = 0; i < g.n_modules; i++) {
        CHECK_EQ(gsd_part_len(&g, (int)i), 0);
        CHECK(!g.modules[i].has_reference);
    }
}

static void user_prm(void)
{
    uint8_t prm[GSD_MAX_USER_PRM];
    int len = gsd_default_prm(&g, NULL, 0, prm, sizeof prm);
    CHECK_BYTES(prm, len, 0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    /* the modules carry no parameters: one configured adds nothing */
    const size_t param_3pd = 7;
    len = gsd_default_prm(&g, &param_3pd, 1, prm, sizeof prm);
    CHECK_EQ(len, 9);
    const size_t bad = 20;
    CHECK_EQ(gsd_default_prm(&g, &bad, 1, prm, sizeof prm), -1);
    CHECK_EQ(gsd_default_prm(&g, NULL, 0, prm, 8), -1);
}

static void consistent(void)
{
    gsd_problem_t p[8];
    size_t n = gsd_check(&g, p, 8);
    for (size_t i = 0; i < n && i < 8u; i++) fprintf(stderr, "line %u: %s\n", p[i].line,
                                                     p[i].text);
    CHECK_EQ(n, 0);
}

static void test_sewa6003(void)
{
    if (!load("SEWA6003.GSD")) return;
    common(23);
    modules();
    user_prm();
    consistent();
    uint32_t v = 0;
    CHECK(gsd_key(&g, GSD_K_GSD_REVISION, &v) && v == 3u);
    CHECK_STR(gsd_text(&g, GSD_S_MODEL_NAME), "MOVIDRIVE DFP21B/MCH (DP-V1)");
    CHECK(gsd_key(&g, GSD_K_DPV1_SLAVE, &v) && v == 1u);
    CHECK(gsd_key(&g, GSD_K_C1_READ_WRITE_SUPP, &v) && v == 1u);
    CHECK(gsd_key(&g, GSD_K_C1_MAX_DATA_LEN, &v) && v == 240u);
    CHECK(gsd_key(&g, GSD_K_C2_MAX_COUNT_CHANNELS, &v) && v == 2u);
    CHECK(gsd_key(&g, GSD_K_C2_RESPONSE_TIMEOUT, &v) && v == 100u);
    CHECK(gsd_key(&g, GSD_K_MAX_INITIATE_PDU_LENGTH, &v) && v == 52u);
    CHECK(gsd_key(&g, GSD_K_WD_BASE_1MS_SUPP, &v) && v == 1u);
    CHECK(gsd_key(&g, GSD_K_IDENT_MAINTENANCE_SUPP, &v) && v == 1u);
    CHECK(!gsd_key(&g, GSD_K_DIAGNOSTIC_ALARM_SUPP, &v));
    CHECK_EQ(g.n_defs, 0);
    CHECK_EQ(g.n_refs, 0);
    CHECK_EQ(g.n_consts, 1);
    CHECK_EQ(g.modules[0].line, 133);
    CHECK_EQ(g.modules[0].end_line, 134);
}

static void test_sew6003(void)
{
    if (!load("SEW_6003.GSD")) return;
    common(17);
    modules();
    user_prm();
    consistent();
    uint32_t v = 0;
    CHECK(gsd_key(&g, GSD_K_GSD_REVISION, &v) && v == 1u);
    CHECK_STR(gsd_text(&g, GSD_S_MODEL_NAME), "MOVIDRIVE+DFP21");
    for (int k = GSD_K_DPV1_SLAVE; k <= GSD_K_DPV1_LAST; k++) CHECK_EQ(g.key_line[k], 0);
    CHECK_EQ(g.n_defs, 1);
    const gsd_prm_def_t *d = gsd_find_def(&g, 1);
    CHECK(d != NULL);
    if (d == NULL) return;
    CHECK_STR(gsd_chars(&g, d->name), "Diagnostic alarm");
    CHECK_EQ(d->type, GSD_T_UNSIGNED8);
    CHECK_EQ(d->def, 1);
    CHECK_EQ(d->min, 0);
    CHECK_EQ(d->max, 1);
    CHECK_EQ(d->value_count, 0);
    CHECK_EQ(d->text_ref, 1);
    CHECK_EQ(d->line, 105);
    CHECK_STR(gsd_prm_text(&g, 1, 0), "On");
    CHECK_STR(gsd_prm_text(&g, 1, 1), "Off");
    CHECK(gsd_prm_text(&g, 1, 2) == NULL);
    CHECK_EQ(g.n_refs, 1);
    CHECK_EQ(g.refs[0].offset, 8);
    CHECK_EQ(g.refs[0].number, 1);
    CHECK_EQ(g.refs[0].module, GSD_GLOBAL);
    CHECK_EQ(g.refs[0].line, 113);
    CHECK_EQ(g.modules[0].line, 119);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_gsd_files GSD_DIR\n");
        return 2;
    }
    dir = argv[1];
    RUN_TEST(test_sewa6003);
    RUN_TEST(test_sew6003);
    return check_report();
}
