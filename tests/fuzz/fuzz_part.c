/* libFuzzer harness for part files (spec/part.md) and the merge that replays them
 * (bake/dist/dist.c, bake/pipeline/bake_dist.c). A part comes from another machine, so the merge must
 * treat it as hostile: every input is checked as it is, then once more with its checksums and
 * identity fields repaired (the plan and options hashes, unit 0 of 1, the receiver range its count
 * gives) so that mutations reach the run records and the values the merge replays into the
 * pipeline (NaN, Inf, huge or negative radiance, foreign masks, pass counts). Such a part is then
 * merged over tests/fuzz/part_scene.gltf. A crash or sanitizer report is a finding; a refusal is
 * an answer; a merge that succeeds must give a container the library's validator accepts.
 * Run from the repository root (the scene's path is relative; LBK_FUZZ_PART_SCENE overrides). */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "bake/dist/dist.h"
#include "lbk/bake.h"
#include "lbk/bake_dist.h"
#include "lbk/byteorder.h"
#include "lbk/lbk.h"
#include "lbk/validate.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { HEADER = 96 };
static const uint64_t plan_hash = 0x6c626b2d66757a7aull; /* any non-zero value: the harness is the plan */

typedef struct harness {
    int ready;
    const char *scene;
    lbk_bake_desc desc;
    uint64_t options_hash; /* what the unit stamped (offset 80): the merge's own options */
} harness;

static harness H; /* libFuzzer's interface has no user pointer: the harness's one setting lives here */

/* The options every part was baked with and every merge uses: small, one thread, a fixed
 * schedule (what a distributed bake needs). */
static void set_desc(lbk_bake_desc *d)
{
    memset(d, 0, sizeof *d);
    d->size = sizeof *d;
    d->threads = 1;
    d->target_error = -1;
    d->max_samples = 4;
    d->texel_density = 2;
    d->glg_spacing = 8;
}

/* Bakes the scene's one unit once, to learn the options hash the merge will expect. */
static void setup(void)
{
    H.scene = getenv("LBK_FUZZ_PART_SCENE");
    if (!H.scene) H.scene = "tests/fuzz/part_scene.gltf";
    set_desc(&H.desc);
    void *part = NULL;
    size_t n = 0;
    if (lbk_bake_unit_from_file(H.scene, &H.desc, plan_hash, 1, 0, &part, &n) || n < HEADER) {
        fprintf(stderr, "fuzz_part: cannot bake %s (run from the repository root)\n", H.scene);
        abort();
    }
    H.options_hash = lbk_rd64((const uint8_t *)part + 80);
    lbk_bake_part_free(part);
    H.ready = 1;
}

/* Every run record's receiver range set to [0, receivers) (unit 0 of 1 holds every run whole),
 * walking the records as far as their passes and masks give sizes. */
static void repair_ranges(uint8_t *p, size_t size, uint64_t receivers)
{
    size_t at = HEADER;
    while (size - at >= BK_PART_RUN_HEADER_SIZE) {
        lbk_wr64(p + at + 96, 0);
        lbk_wr64(p + at + 104, receivers);
        const uint32_t passes = lbk_rd32(p + at), mask = lbk_rd32(p + at + 4);
        if (passes == 0 || passes > 32 || mask > 15 || receivers > ((uint64_t)1 << 30)) return;
        const size_t n = bk_part_run_size(receivers, passes, mask);
        if (n == 0 || n > size - at) return;
        at += n;
    }
}

/* A copy of the input that passes every identity and checksum test the fuzzer cannot forge. */
static uint8_t *repaired(const uint8_t *data, size_t size)
{
    uint8_t *p = malloc(size);
    if (!p) abort();
    memcpy(p, data, size);
    uint64_t receivers = lbk_rd64(p + 32) & (((uint64_t)1 << 40) - 1);
    uint32_t runs = lbk_rd32(p + 40); /* the input's own total_runs, kept: the records must match it */
    if (runs == 0 || runs > 65536) runs = 1;
    lbk_wr64(p + 16, plan_hash);
    lbk_wr32(p + 24, 1);
    lbk_wr32(p + 28, 0);
    lbk_wr64(p + 32, receivers);
    lbk_wr32(p + 40, runs);      /* format 2: unit 0 of 1 holds runs [0, runs) */
    lbk_wr32(p + 44, 0);
    lbk_wr64(p + 48, 0);
    lbk_wr32(p + 56, runs);
    lbk_wr32(p + 60, 0);
    repair_ranges(p, size, receivers);
    lbk_wr64(p + 64, size - HEADER);
    lbk_wr64(p + 72, XXH64(p + HEADER, size - HEADER, 0));
    lbk_wr64(p + 80, H.options_hash);
    lbk_wr64(p + 88, XXH64(p, 88, 0));
    return p;
}

static void merge(const uint8_t *part, size_t size)
{
    const void *parts[1] = {part};
    size_t sizes[1] = {size};
    lbk_bake_output *out = NULL;
    if (lbk_bake_merge_from_file(H.scene, &H.desc, plan_hash, 1, parts, sizes, 1, &out)) return;
    void *bytes = NULL;
    size_t n = 0;
    if (lbk_bake_output_container(out, &bytes, &n)) abort();
    lbk_validate_summary s;
    if (lbk_validate_memory(bytes, n, NULL, NULL, NULL, &s) || s.fatal || s.errors) {
        fprintf(stderr, "fuzz_part: a merged container does not validate (%u fatal, %u errors)\n", s.fatal, s.errors);
        abort();
    }
    lbk_free(NULL, bytes);
    lbk_bake_output_free(out);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!H.ready) setup();
    lbk_bake_part_info info;
    char err[256];
    (void)lbk_bake_part_check(data, size, 0, 0, &info, err, sizeof err);
    if (size < HEADER) return 0;
    uint8_t *p = repaired(data, size);
    if (lbk_bake_part_check(p, size, plan_hash, 1, &info, err, sizeof err) == LBK_OK) merge(p, size);
    free(p);
    return 0;
}
