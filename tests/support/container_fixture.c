/* Fixed-content containers for tests (see container_fixture.h). */
#include "container_fixture.h"

#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "lbk/meta.h"
#include "lbk/objects.h"
#include "lbk/report.h"

const uint8_t fixture_xtra[40] = "unknown optional section: readers skip";

int fixture_meta(void **out, size_t *size)
{
    const lbk_meta_pair pairs[] = {
        {"writer", "lbk"},
        {"writer.version", "1.0.0"},
        {"scene.hash", "0123456789abcdef"},
        {"bake.seed", "1"},
        {"bake.preset", "fast"},
        {"revision", "r42 \xc3\xa9t\xc3\xa9"}, /* UTF-8: "été" */
    };
    return lbk_meta_build(pairs, sizeof pairs / sizeof pairs[0], NULL, out, size) != LBK_OK;
}

int fixture_report(void **out, size_t *size)
{
    const lbk_report_record records[] = {
        {0.0, 1000000, 4, 2, 0.5f, 0.25f},
        {0.0, 2000000, 8, 2, 0.35f, 0.18f},
        {0.0, 4000000, 16, 2, 0.25f, 0.125f},
        {0.0, 8000000, 32, 2, 0.125f, 0.0625f},
    };
    const lbk_report rep = {.status = LBK_BAKE_TARGET_REACHED, .max_samples_per_texel = 256,
        .time_limit_seconds = 0.0, .target_rel_rmse = 0.15f, .records = records, .record_count = 4};
    return lbk_report_build(&rep, NULL, out, size) != LBK_OK;
}

int fixture_objects(void **out, size_t *size)
{
    const lbk_object objects[] = {
        {{"floor", 5}, 0x1111222233334444ull, LBK_REPRESENTATION_NONE, 0, 0, 0, 0, 0},
        {{"wall_north", 10}, 0x5555666677778888ull, LBK_REPRESENTATION_NONE, 0, 0, 0, 0, 0},
        {{"lamp", 4}, 0x99990000aaaabbbbull, LBK_REPRESENTATION_NONE, 0, 0, 0, 0, 0},
    };
    return lbk_objects_build(objects, 3, NULL, out, size) != LBK_OK;
}

int fixture_small_container(uint32_t alignment, void **out, size_t *size)
{
    void *meta = NULL, *rept = NULL, *objs = NULL;
    size_t meta_n, rept_n, objs_n;
    lbk_writer *w = NULL;
    int rc = 1;
    lbk_write_options wo = {.section_alignment = alignment};
    lbk_section_options zstd = {.compression = LBK_COMPRESSION_ZSTD, .zstd_level = 3};
    if (fixture_meta(&meta, &meta_n) || fixture_report(&rept, &rept_n) || fixture_objects(&objs, &objs_n)) goto out;
    if (lbk_writer_open(&wo, &w) != LBK_OK) goto out;
    /* Added out of canonical order on purpose: the writer sorts. */
    if (lbk_writer_section_add(w, LBK_FOURCC('X', 'T', 'R', 'A'), fixture_xtra, sizeof fixture_xtra, NULL) ||
        lbk_writer_section_add(w, LBK_SECTION_OBJS, objs, objs_n, NULL) ||
        lbk_writer_section_add(w, LBK_SECTION_REPT, rept, rept_n, &zstd) ||
        lbk_writer_section_add(w, LBK_SECTION_META, meta, meta_n, NULL))
        goto out;
    void *bytes;
    if (lbk_writer_to_memory(w, &bytes, size) != LBK_OK) goto out;
    *out = malloc(*size);
    if (*out) memcpy(*out, bytes, *size);
    lbk_free(NULL, bytes);
    rc = *out == NULL;
out:
    lbk_writer_close(w);
    lbk_free(NULL, meta);
    lbk_free(NULL, rept);
    lbk_free(NULL, objs);
    return rc;
}

static uint32_t rd32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static void wr64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(v >> (8 * i));
}

void fixture_fix_checksums(uint8_t *file)
{
    uint32_t n = rd32(file + 32);
    if (n <= LBK_MAX_SECTIONS) wr64(file + 48, XXH3_64bits(file + 64, (size_t)n * 48));
    wr64(file + 56, XXH3_64bits(file, 56));
}
