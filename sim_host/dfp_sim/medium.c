/* --port / --bus / --lcm-url. See medium.h. */
#include "medium.h"

#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "lcm_bridge/lcm_segment.h"

int medium_option(medium_opts_t *m, int argc, char **argv, int *i)
{
    const char **slot = NULL;
    if (strcmp(argv[*i], "--port") == 0) {
        slot = &m->dev;
    } else if (strcmp(argv[*i], "--bus") == 0) {
        slot = &m->bus;
    } else if (strcmp(argv[*i], "--lcm-url") == 0) {
        slot = &m->lcm_url;
    } else {
        return 0;
    }
    return (*slot = cli_value(argc, argv, i)) != NULL ? 1 : -1;
}

bool medium_check(const medium_opts_t *m, const char *cmd)
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
    return true;
}

const char *medium_name(const medium_opts_t *m, const char *opened_url, char *buf, size_t n)
{
    if (m->bus == NULL) {
        return m->dev;
    }
    (void)snprintf(buf, n, "LCM segment %s (%s)", dfp_lcm_segment_channel(m->bus), opened_url);
    return buf;
}
