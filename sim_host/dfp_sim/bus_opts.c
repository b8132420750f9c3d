/* --bus-profile, --tsl ... See bus_opts.h. */
#include "bus_opts.h"

#include <stddef.h>

#include "cli.h"

#define BUS(field) offsetof(bus_opts_t, field)

static const cli_choice_t profile_words[] = {
    {"dp", FDL_BUS_PROFILE_DP, false},
    {"usb", FDL_BUS_PROFILE_USB, false},
    {NULL, 0, false},
};

const cli_opt_t bus_options[10] = {
    {CLI_OPT("--bus-profile", "dp|usb", CLI_CHOICE, BUS(profile)), .choices = profile_words,
     .bad = "--bus-profile: '%s' is not dp or usb"},
    {CLI_OPT("--tsl", "BITS", CLI_U32, BUS(tsl)), .min = 37, .max = 16777215u,
     .seen = CLI_SEEN(bus_opts_t, tsl_seen)},
    {CLI_OPT("--min-tsdr", "BITS", CLI_U32, BUS(min_tsdr)), .min = 11, .max = 65535u,
     .seen = CLI_SEEN(bus_opts_t, min_tsdr_seen)},
    {CLI_OPT("--max-tsdr", "BITS", CLI_U32, BUS(max_tsdr)), .min = 11, .max = 16777215u,
     .seen = CLI_SEEN(bus_opts_t, max_tsdr_seen)},
    {CLI_OPT("--tset", "BITS", CLI_U32, BUS(tset)), .min = 0, .max = 255,
     .seen = CLI_SEEN(bus_opts_t, tset_seen)},
    {CLI_OPT("--tqui", "BITS", CLI_U32, BUS(tqui)), .min = 0, .max = 255,
     .seen = CLI_SEEN(bus_opts_t, tqui_seen)},
    {CLI_OPT("--ttr", "BITS", CLI_U32, BUS(ttr)), .min = 256, .max = UINT32_MAX,
     .seen = CLI_SEEN(bus_opts_t, ttr_seen)},
    {CLI_OPT("--gap-factor", "G", CLI_U32, BUS(gap)), .min = 1, .max = 100,
     .seen = CLI_SEEN(bus_opts_t, gap_seen)},
    {CLI_OPT("--hsa", "N", CLI_U32, BUS(hsa)), .min = 1, .max = 126,
     .seen = CLI_SEEN(bus_opts_t, hsa_seen)},
    {CLI_OPT("--max-retry", "N", CLI_U32, BUS(retry)), .min = 0, .max = 7,
     .seen = CLI_SEEN(bus_opts_t, retry_seen)},
};

void bus_opts_defaults(bus_opts_t *o)
{
    *o = (bus_opts_t){.profile = -1};
}

bool bus_opts_apply(const bus_opts_t *o, const char *cmd, uint32_t baud, bool wall_clock,
                    fdl_bus_params_t *out)
{
    fdl_bus_profile_t profile = o->profile >= 0 ? (fdl_bus_profile_t)o->profile
                                : wall_clock     ? FDL_BUS_PROFILE_USB
                                                 : FDL_BUS_PROFILE_DP;
    fdl_bus_params_default(out, baud, profile);
    if (o->tsl_seen) out->tsl_bits = o->tsl;
    if (o->min_tsdr_seen) out->min_tsdr_bits = (uint16_t)o->min_tsdr;
    if (o->max_tsdr_seen) out->max_tsdr_bits = o->max_tsdr;
    if (o->tset_seen) out->tset_bits = (uint8_t)o->tset;
    if (o->tqui_seen) out->tqui_bits = (uint8_t)o->tqui;
    if (o->ttr_seen) out->ttr_bits = o->ttr;
    if (o->gap_seen) out->gap_factor = (uint8_t)o->gap;
    if (o->hsa_seen) out->hsa = (uint8_t)o->hsa;
    if (o->retry_seen) out->max_retry = (uint8_t)o->retry;
    char why[160];
    if (!fdl_bus_params_check(out, why, sizeof why)) {
        cli_error("%s: bus parameters: %s", cmd, why);
        return false;
    }
    return true;
}

bool bus_opts_own_ok(const fdl_bus_params_t *p, const char *cmd, const char *opt, uint32_t own)
{
    char why[160]; /* own comes from a table that stops at 126 */
    if (!fdl_bus_address_ok(p, (uint8_t)own, why, sizeof why)) {
        cli_error("%s: %s %u: %s (give --hsa %u or more, as every master of the segment)", cmd,
                  opt, own, why, own);
        return false;
    }
    return true;
}

bool bus_opts_given(const bus_opts_t *o)
{
    return o->profile >= 0 || o->tsl_seen || o->min_tsdr_seen || o->max_tsdr_seen ||
           o->tset_seen || o->tqui_seen || o->ttr_seen || o->gap_seen || o->hsa_seen ||
           o->retry_seen;
}
