/* What a bake call hands back (lbk_bake_output): the container's writer and the report, all in
 * the caller's allocator. */
#include <stdlib.h>
#include <string.h>

#include "bake/pipeline/pipeline.h"

static int has_custom(const lbk_allocator *a) { return a->alloc && a->free; }

void *bk_output_alloc(const lbk_bake_output *out, size_t size)
{
    if (size == 0) size = 1;
    return has_custom(&out->allocator) ? out->allocator.alloc(out->allocator.user, size) : malloc(size);
}

void bk_output_free_mem(const lbk_bake_output *out, void *p)
{
    if (!p) return;
    if (has_custom(&out->allocator)) out->allocator.free(out->allocator.user, p);
    else free(p);
}

void lbk_bake_output_free(lbk_bake_output *out)
{
    if (!out) return;
    lbk_writer_close(out->writer);
    bk_output_free_mem(out, out->passes);
    bk_output_free_mem(out, out->pass_errors);
    bk_output_free_mem(out, out->set_runs);
    bk_output_free_mem(out, out->set_labels);
    bk_output_free_mem(out, out->set_estimates);
    bk_output_free_mem(out, out->set_names);
    bk_output_free_mem(out, out->object_estimates);
    bk_output_free_mem(out, out->object_names);
    bk_output_free_mem(out, out->object_checks);
    bk_output_free_mem(out, out->llg_estimates);
    bk_output_free_mem(out, out->llg_names);
    bk_output_free_mem(out, out->input);
    lbk_allocator a = out->allocator;
    lbk_bake_output tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.allocator = a;
    bk_output_free_mem(&tmp, out);
}

lbk_writer *lbk_bake_output_writer(lbk_bake_output *out) { return out ? out->writer : NULL; }

lbk_result lbk_bake_output_container(lbk_bake_output *out, void **bytes, size_t *size)
{
    if (!out || !bytes || !size) return LBK_ERR_INVALID_ARGUMENT;
    return lbk_writer_to_memory(out->writer, bytes, size);
}

lbk_result lbk_bake_output_write_file(lbk_bake_output *out, const char *path)
{
    if (!out || !path) return LBK_ERR_INVALID_ARGUMENT;
    return lbk_writer_to_file(out->writer, path);
}

const lbk_bake_report *lbk_bake_output_report(const lbk_bake_output *out) { return out ? &out->report : NULL; }
