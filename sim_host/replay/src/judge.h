/* Inside the replay engine: judging a request's answer when its window closes (judge.c). */
#ifndef REPLAY_JUDGE_H
#define REPLAY_JUDGE_H

#include "replay/replay.h"

/* The ring keeps a few more than REPLAY_CONTEXT telegrams: when a request's window closes, the
 * request and the card's answer are the newest entries, and the context lies before them. */
#define RING_SIZE (sizeof(((replay_t *)0)->ring) / sizeof(((replay_t *)0)->ring[0]))

/* The pending request's window closes: its recorded answer and the card's are compared (octets
 * the mask leaves out skipped), the counts kept, a mismatch handed to on_mismatch and the first
 * one kept with its context. Nothing when no request is pending. */
void replay_judge(replay_t *r);

#endif
