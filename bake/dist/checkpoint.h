/* Checkpoints of a bake (lbk bake --checkpoint DIR / --resume DIR / --continue DIR;
 * bake/dist/DIST.md §Resume): after every pass of every transport run, the run's whole state in
 * DIR/run-R.ckpt, written atomically (a temporary file, fsync, rename), so a bake killed at any
 * moment resumes from its last finished pass and ends byte-identical to an uninterrupted one.
 * The files are for the same lbk build on the same kind of machine (native byte order). */
#ifndef BK_CHECKPOINT_H
#define BK_CHECKPOINT_H

#include <stdint.h>

#include "bake/transport/transport.h"
#include "lbk/lbk.h"

typedef struct bk_ckpt bk_ckpt;

/* resume 0: a fresh bake (the run files of an earlier one in dir are removed); 1: runs whose
 * file exists continue from it. options_hash: the options that must not change in between. */
lbk_result bk_ckpt_create(const char *dir, int resume, uint64_t options_hash, bk_ckpt **out, char *err, size_t err_len);
void bk_ckpt_destroy(bk_ckpt *c);
const bk_transport_checkpoint *bk_ckpt_transport(const bk_ckpt *c);
/* The first error's text ("" none). */
const char *bk_ckpt_error(const bk_ckpt *c);
/* That error's result: LBK_ERR_IO, LBK_ERR_BAD_INPUT (another bake's or a corrupt checkpoint). */
lbk_result bk_ckpt_code(const bk_ckpt *c);
/* Runs that were resumed from a file, and how many passes they skipped in all. */
void bk_ckpt_counts(const bk_ckpt *c, int *resumed_runs, int *skipped_passes);

#endif
