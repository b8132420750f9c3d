/* A text document the bus loop publishes to client threads (the bus monitor's JSON, served as
 * GET /api/v1/bus), in the way rig_ctl.h publishes its snapshot: RIG_DOC_BUFS fixed buffers; a
 * client pins the newest complete one with an atomic count and copies it; the loop fills one
 * nobody has pinned, or skips that publication when there is none. The loop never waits on a
 * client, and a client never sees a document half written.
 *
 * One writer (the loop's thread), any number of readers. Large (RIG_DOC_BUFS * RIG_DOC_CAP):
 * static or heap storage, never on a thread's stack. */
#ifndef RIG_RIG_DOC_H
#define RIG_RIG_DOC_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define RIG_DOC_BUFS 4u /* the current one, the one being filled, two being read */
/* The monitor's JSON is 2..3 KB per DP slave as lines have them (cfg, prm, diag and I/O in hex,
 * the DFP21B's names, the figures), about 380 KB for 126 slaves; a slave whose Set_Prm, Chk_Cfg,
 * diagnosis, outputs and inputs all have their 244 octets takes 4.2 KB, 540 KB for 128
 * stations. A buffer has room for that and the events. Pages only count once written: a line
 * of a few stations keeps a few KB of each resident. */
#define RIG_DOC_CAP ((size_t)1024u * 1024u)
#define RIG_DOC_WRITER 0x80000000u /* in use[i]: the loop is filling that buffer */

typedef struct rig_doc {
    char text[RIG_DOC_BUFS][RIG_DOC_CAP];
    size_t len[RIG_DOC_BUFS];
    atomic_uint use[RIG_DOC_BUFS]; /* clients copying text[i], + RIG_DOC_WRITER while filled */
    atomic_uint current;           /* text[current] is the newest complete document */
    atomic_bool published;         /* current holds a document (false until the first one) */
    /* loop side */
    int filling;                   /* the buffer between rig_doc_begin and its end; -1: none */
    uint64_t skipped;              /* publications skipped, every other buffer being read */
    uint64_t too_large;            /* documents that did not fit in RIG_DOC_CAP */
} rig_doc_t;

void rig_doc_init(rig_doc_t *d);

/* Loop side. A buffer of RIG_DOC_CAP octets to write the next document into, or NULL when
 * every buffer but the current one is being read (this publication is skipped). End it with
 * rig_doc_commit or rig_doc_abandon. */
char *rig_doc_begin(rig_doc_t *d);
/* The document of len octets written since rig_doc_begin becomes the current one. */
void rig_doc_commit(rig_doc_t *d, size_t len);
/* Nothing is published (the document did not fit); the current one stays. */
void rig_doc_abandon(rig_doc_t *d);
/* begin, copy, commit: false when skipped or len > RIG_DOC_CAP. */
bool rig_doc_publish(rig_doc_t *d, const char *text, size_t len);

/* Client side: a heap copy (malloc, NUL-terminated) of the newest document and its length, or
 * NULL when none has been published yet or memory ran out (*len = 0). Never waits for the
 * loop. */
char *rig_doc_copy(rig_doc_t *d, size_t *len);

#endif
