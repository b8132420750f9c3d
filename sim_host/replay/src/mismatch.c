/* The kept mismatches (replay/mismatch.h): spooled to a temporary file, fixed header then the
 * three telegrams' octets, so a list of every mismatch of a long capture takes disk, not
 * memory. */
#include "replay/mismatch.h"

#include <errno.h>
#include <string.h>

size_t replay_listed_diffs(const replay_listed_t *m, uint16_t *out, size_t max)
{
    if (!m->expected_present || !m->actual_present) {
        return 0u;
    }
    size_t common = m->expected_len < m->actual_len ? m->expected_len : m->actual_len;
    size_t n = 0;
    for (size_t i = 0; i < common; i++) {
        if (m->expected[i] != m->actual[i] && (m->mask[i / 8u] & (1u << (i % 8u))) == 0u) {
            if (n < max) {
                out[n] = (uint16_t)i;
            }
            n++;
        }
    }
    return n;
}

void replay_list_init(replay_list_t *l, uint64_t max)
{
    memset(l, 0, sizeof *l);
    l->max = max;
}

static void list_failed(replay_list_t *l, const char *what)
{
    if (!l->failed) {
        snprintf(l->error, sizeof l->error, "%s: %s", what, strerror(errno));
    }
    l->failed = true;
}

void replay_list_add(void *list, const replay_listed_t *m)
{
    replay_list_t *l = list;
    if (l->kept >= l->max || l->failed) {
        return;
    }
    if (l->spool == NULL && (l->spool = tmpfile()) == NULL) {
        list_failed(l, "no temporary file for the mismatch list");
        return;
    }
    size_t head = offsetof(replay_listed_t, request);
    if (fwrite(m, head, 1, l->spool) != 1u ||
        fwrite(m->request, 1, m->request_len, l->spool) != m->request_len ||
        fwrite(m->expected, 1, m->expected_len, l->spool) != m->expected_len ||
        fwrite(m->actual, 1, m->actual_len, l->spool) != m->actual_len) {
        list_failed(l, "the mismatch list could not be written");
        return;
    }
    l->kept++;
}

bool replay_list_rewind(replay_list_t *l)
{
    if (l->spool == NULL || l->failed) {
        return false;
    }
    if (fflush(l->spool) != 0 || fseek(l->spool, 0, SEEK_SET) != 0) {
        list_failed(l, "the mismatch list could not be read back");
        return false;
    }
    return true;
}

bool replay_list_next(replay_list_t *l, replay_listed_t *out)
{
    if (l->spool == NULL || l->failed) {
        return false;
    }
    size_t head = offsetof(replay_listed_t, request);
    if (fread(out, head, 1, l->spool) != 1u) {
        return false; /* the end */
    }
    if (out->request_len > CAP_MAX_RECORD || out->expected_len > CAP_MAX_RECORD ||
        out->actual_len > CAP_MAX_RECORD ||
        fread(out->request, 1, out->request_len, l->spool) != out->request_len ||
        fread(out->expected, 1, out->expected_len, l->spool) != out->expected_len ||
        fread(out->actual, 1, out->actual_len, l->spool) != out->actual_len) {
        list_failed(l, "the mismatch list could not be read back");
        return false;
    }
    return true;
}

void replay_list_close(replay_list_t *l)
{
    if (l->spool != NULL) {
        (void)fclose(l->spool);
        l->spool = NULL;
    }
}
