/* Transport checkpoints in memory (bk_transport_checkpoint) for resume tests: every pass's
 * state is saved; a load hands back the state saved after pass `at` (0-based; -1: none, the run
 * starts afresh). */
#ifndef TESTS_MEM_CHECKPOINT_H
#define TESTS_MEM_CHECKPOINT_H

#include "bake/transport/transport.h"

typedef struct mem_ckpt {
    int at, saved;
    bk_transport_state st[BK_TRANSPORT_MAX_PASSES];
} mem_ckpt;

/* An empty store (at = -1) and the callbacks that use it. */
void mem_ckpt_init(mem_ckpt *m, bk_transport_checkpoint *ck);
/* Frees the states saved after pass `keep` - 1 (saved = keep): a run resumed after pass keep - 1
 * saves the later ones again. mem_ckpt_drop(m, 0) frees them all. */
void mem_ckpt_drop(mem_ckpt *m, int keep);

#endif
