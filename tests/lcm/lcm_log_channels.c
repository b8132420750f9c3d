/* Test helper: how many events each channel has in an LCM log, one "CHANNEL COUNT" line per
 * channel in order of first appearance (the shell tests count card states and parameter
 * services without decoding them). Exit 1 when the log cannot be opened. */
#include <lcm/eventlog.h>
#include <stdio.h>
#include <string.h>

#define MAX_CHANNELS 32

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: lcm_log_channels LOG\n");
        return 2;
    }
    lcm_eventlog_t *log = lcm_eventlog_create(argv[1], "r");
    if (log == NULL) {
        fprintf(stderr, "cannot open %s\n", argv[1]);
        return 1;
    }
    static char names[MAX_CHANNELS][64];
    static unsigned long counts[MAX_CHANNELS];
    int n = 0;
    lcm_eventlog_event_t *ev;
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        int i = 0;
        while (i < n && strcmp(names[i], ev->channel) != 0) {
            i++;
        }
        if (i == n && n < MAX_CHANNELS) {
            snprintf(names[n++], sizeof names[0], "%s", ev->channel);
        }
        if (i < n) {
            counts[i]++;
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    for (int i = 0; i < n; i++) {
        printf("%s %lu\n", names[i], counts[i]);
    }
    return 0;
}
