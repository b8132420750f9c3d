#include "rig/rig_doc.h"

#include <stdlib.h>
#include <string.h>

void rig_doc_init(rig_doc_t *d)
{
    for (unsigned i = 0; i < RIG_DOC_BUFS; i++) {
        d->len[i] = 0;
        atomic_init(&d->use[i], 0u);
    }
    atomic_init(&d->current, 0u);
    atomic_init(&d->published, false);
    d->filling = -1;
    d->skipped = 0;
    d->too_large = 0;
}

char *rig_doc_begin(rig_doc_t *d)
{
    if (d->filling >= 0) {
        rig_doc_abandon(d);
    }
    unsigned cur = atomic_load_explicit(&d->current, memory_order_relaxed);
    for (unsigned i = 0; i < RIG_DOC_BUFS; i++) {
        unsigned idle = 0u;
        if (i != cur && atomic_compare_exchange_strong_explicit(
                            &d->use[i], &idle, RIG_DOC_WRITER, memory_order_acquire,
                            memory_order_relaxed)) {
            d->filling = (int)i;
            return d->text[i];
        }
    }
    d->skipped++;
    return NULL;
}

void rig_doc_commit(rig_doc_t *d, size_t len)
{
    int b = d->filling;
    if (b < 0) {
        return;
    }
    if (len > RIG_DOC_CAP) {
        d->too_large++;
        rig_doc_abandon(d);
        return;
    }
    d->len[b] = len;
    d->filling = -1;
    atomic_fetch_sub_explicit(&d->use[b], RIG_DOC_WRITER, memory_order_release);
    atomic_store_explicit(&d->current, (unsigned)b, memory_order_release);
    atomic_store_explicit(&d->published, true, memory_order_release);
}

void rig_doc_abandon(rig_doc_t *d)
{
    int b = d->filling;
    if (b >= 0) {
        d->filling = -1;
        atomic_fetch_sub_explicit(&d->use[b], RIG_DOC_WRITER, memory_order_release);
    }
}

bool rig_doc_publish(rig_doc_t *d, const char *text, size_t len)
{
    if (len > RIG_DOC_CAP) {
        d->too_large++;
        return false;
    }
    char *buf = rig_doc_begin(d);
    if (buf == NULL) {
        return false;
    }
    memcpy(buf, text, len);
    rig_doc_commit(d, len);
    return true;
}

/* Pins the current buffer and copies it, as rig_ctl_snapshot does: a buffer the loop claimed
 * between the load of current and the pin is let go and the new current one taken; a pinned
 * buffer is never claimed, so the copy is of one whole document. */
char *rig_doc_copy(rig_doc_t *d, size_t *len)
{
    *len = 0;
    if (!atomic_load_explicit(&d->published, memory_order_acquire)) {
        return NULL;
    }
    for (;;) {
        unsigned i = atomic_load_explicit(&d->current, memory_order_acquire);
        unsigned use = atomic_fetch_add_explicit(&d->use[i], 1u, memory_order_acquire);
        if ((use & RIG_DOC_WRITER) == 0u) {
            size_t n = d->len[i];
            char *out = malloc(n + 1u);
            if (out != NULL) {
                memcpy(out, d->text[i], n);
                out[n] = '\0';
                *len = n;
            }
            atomic_fetch_sub_explicit(&d->use[i], 1u, memory_order_release);
            return out;
        }
        atomic_fetch_sub_explicit(&d->use[i], 1u, memory_order_release);
    }
}
