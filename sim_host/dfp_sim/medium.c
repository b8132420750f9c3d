/* --port / --bus / --lcm-url. See medium.h. */
#include "medium.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "lcm_bridge/lcm_segment.h"

const cli_opt_t medium_options[4] = {
    {CLI_OPT("--port", "DEV", CLI_TEXT, offsetof(medium_opts_t, dev))},
    {CLI_OPT("--bus", "lcm:CHANNEL", CLI_TEXT, offsetof(medium_opts_t, bus))},
    {CLI_OPT("--lcm-url", "URL", CLI_TEXT, offsetof(medium_opts_t, lcm_url))},
    {CLI_OPT("--key", "FILE", CLI_TEXT, offsetof(medium_opts_t, key_file))},
};

bool medium_check(medium_opts_t *m, const char *cmd)
{
    if (m->dev != NULL && m->bus != NULL) {
        cli_error("%s: --port and --bus exclude each other", cmd);
        return false;
    }
    if (m->bus != NULL && dfp_lcm_segment_channel(m->bus) == NULL) {
        cli_error("%s: --bus '%s': use lcm:CHANNEL (1..63 of A-Z a-z 0-9 _ . -)", cmd, m->bus);
        return false;
    }
    if (m->lcm_url != NULL && m->bus == NULL) {
        cli_error("%s: --lcm-url belongs to --bus lcm:CHANNEL", cmd);
        return false;
    }
    if (m->key_file != NULL && m->bus == NULL) {
        cli_error("%s: --key belongs to --bus lcm:CHANNEL", cmd);
        return false;
    }
    if (m->key_file != NULL) {
        char err[400];
        if (dfp_seg_key_load(m->key_file, m->key, err, sizeof err) != 0) {
            cli_error("%s: %s", cmd, err);
            return false;
        }
        m->keyed = true;
    }
    return true;
}

const uint8_t *medium_key(const medium_opts_t *m)
{
    return m->keyed ? m->key : NULL;
}

bool medium_check_real_drive(const medium_opts_t *m, const char *cmd, const char *inverter)
{
    if (m->bus == NULL || m->key_file != NULL || inverter == NULL ||
        strncmp(inverter, "can:", 4) != 0) {
        return true;
    }
    const char *ifname = inverter + 4;
    int n = (int)strcspn(ifname, ":");
    cli_error("%s: --bus lcm: without --key lets any process on the LCM group drive the real "
              "MOVIDRIVE on %.*s; give --key FILE", cmd, n, ifname);
    return false;
}

const char *medium_name(const medium_opts_t *m, const char *opened_url, char *buf, size_t n)
{
    if (m->bus == NULL) {
        return m->dev;
    }
    (void)snprintf(buf, n, "LCM segment %s (%s)", dfp_lcm_segment_channel(m->bus), opened_url);
    return buf;
}
