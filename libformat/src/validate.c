/* lbk_validate_*: runs the framing checks (framing.c), verifies and decodes every section, then
 * hands each section's bytes to its validator in dependency order so later sections can
 * cross-check against facts the earlier ones recorded in lbk_vctx. */
#include <stdio.h>

#include "framing.h"
#include "lbk/error_map.h"

static void emit(lbk_vctx *ctx, uint32_t id, uint32_t section_type, uint64_t offset, const char *fmt, va_list ap)
{
    if (ctx->stop) return;
    lbk_issue issue;
    memset(&issue, 0, sizeof issue);
    lbk_severity severity = LBK_SEVERITY_ERROR; /* an ID missing from the registry still invalidates */
    lbk_issue_template(id, &severity);
    issue.id = id;
    issue.severity = severity;
    issue.section_type = section_type;
    issue.offset = offset;
    vsnprintf(issue.message, sizeof issue.message, fmt, ap);
    if (severity == LBK_SEVERITY_FATAL) ctx->summary->fatal++;
    else if (severity == LBK_SEVERITY_ERROR) ctx->summary->errors++;
    else ctx->summary->warnings++;
    if (ctx->callback && ctx->callback(ctx->user, &issue)) ctx->stop = 1;
}

void lbk_vreport(lbk_vctx *ctx, uint32_t id, uint64_t offset_in_section, const char *fmt, ...)
{
    uint64_t offset = offset_in_section;
    if (ctx->section_type != 0)
        offset = ctx->section_offset + (ctx->section_compressed ? 0 : offset_in_section);
    va_list ap;
    va_start(ap, fmt);
    emit(ctx, id, ctx->section_type, offset, fmt, ap);
    va_end(ap);
}

void lbk_vreport_capped(lbk_vctx *ctx, uint32_t *errors, uint16_t reported[100], uint32_t first_id, uint16_t cap,
                        uint32_t id, uint64_t offset_in_section, const char *fmt, va_list ap)
{
    lbk_severity sev = LBK_SEVERITY_ERROR;
    lbk_issue_template(id, &sev);
    if (sev != LBK_SEVERITY_WARNING) (*errors)++;
    if (!ctx) return;
    if (id >= first_id && id < first_id + 100 && reported[id - first_id]++ >= cap) return;
    char msg[160];
    vsnprintf(msg, sizeof msg, fmt, ap);
    lbk_vreport(ctx, id, offset_in_section, "%s", msg);
}

static void vreport_at(lbk_vctx *ctx, uint32_t id, uint32_t type, uint64_t offset, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void vreport_at(lbk_vctx *ctx, uint32_t id, uint32_t type, uint64_t offset, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    emit(ctx, id, type, offset, fmt, ap);
    va_end(ap);
}

static int framing_report(void *user, uint32_t id, lbk_result r, uint32_t type, uint64_t offset, const char *fmt,
                          va_list ap)
{
    (void)r;
    lbk_vctx *ctx = user;
    emit(ctx, id, type, offset, fmt, ap);
    return ctx->stop;
}

typedef void (*section_validator)(lbk_vctx *ctx, const uint8_t *data, size_t size);

static const struct {
    uint32_t type;
    section_validator run;
} dependency_order[] = {
    {LBK_SECTION_META, lbk_validate_meta}, {LBK_SECTION_REPT, lbk_validate_rept}, {LBK_SECTION_LMAP, lbk_validate_lmap},
    {LBK_SECTION_GLG, lbk_validate_glg},   {LBK_SECTION_LLG, lbk_validate_llg},   {LBK_SECTION_OCTP, lbk_validate_octp},
    {LBK_SECTION_OBJS, lbk_validate_objs}, {LBK_SECTION_LMUV, lbk_validate_lmuv}, {LBK_SECTION_DLS, lbk_validate_dls},
    {LBK_SECTION_DOOR, lbk_validate_door}, {LBK_SECTION_TERR, lbk_validate_terr},
};

static const char *load_message(uint32_t id)
{
    switch (id) {
    case 214: return "stored bytes do not match the section checksum";
    case 215: return "zstd frame header unreadable or without content size";
    case 216: return "zstd frame content size differs from decoded_size";
    case 217: return "decoded size exceeds the decoded-bytes cap";
    case 218: return "zstd decompression failed";
    case 219: return "stored bytes are not exactly one zstd frame";
    default: return "section could not be loaded";
    }
}

/* Sections the present ones depend on (spec/container.md §3.2 "needed when"). */
static void check_dependencies(lbk_vctx *ctx)
{
    static const uint32_t need_objs[] = {LBK_SECTION_LMAP, LBK_SECTION_LLG};
    for (size_t i = 0; i < 2; i++)
        if (lbk_vctx_has_section(ctx, need_objs[i]) && !lbk_vctx_has_section(ctx, LBK_SECTION_OBJS)) {
            char cc[5];
            lbk_fourcc_string(need_objs[i], cc);
            vreport_at(ctx, 221, 0, LBK_HEADER_SIZE, "'%s' is present but there is no OBJS section naming its objects",
                       cc);
        }
    if (lbk_vctx_has_section(ctx, LBK_SECTION_DOOR) && !lbk_vctx_has_section(ctx, LBK_SECTION_DLS))
        vreport_at(ctx, 221, 0, LBK_HEADER_SIZE, "'DOOR' is present but there is no 'DLS ' section");
}

/* Every check, over the bytes d; with a reader r (whose bytes d are), each section's checksum and
 * decode go through the reader, which keeps what it decoded, so nothing is decoded twice. */
static lbk_result validate_core(const uint8_t *d, size_t size, const lbk_validate_options *options,
                                lbk_issue_callback callback, void *user, lbk_validate_summary *summary, lbk_reader *rd)
{
    lbk_allocator alloc = {0};
    if (rd) alloc = *lbk_reader_allocator(rd);
    else if (options->allocator && options->allocator->alloc && options->allocator->free) alloc = *options->allocator;

    lbk_framing *fr = lbk_alloc(&alloc, sizeof *fr);
    if (!fr) return LBK_ERR_OUT_OF_MEMORY;
    lbk_vctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.callback = callback;
    ctx.user = user;
    ctx.summary = summary;
    ctx.allocator = &alloc;

    lbk_result result = LBK_OK;
    lbk_framing_parse(d, size, fr, framing_report, &ctx);
    if (!fr->header_ok || ctx.stop) goto done;

    for (uint32_t i = 0; i < fr->count; i++) ctx.present_types[ctx.present_count++] = fr->sections[i].type;
    ctx.required_features = fr->header.required_features;
    if ((ctx.required_features & LBK_FEATURE_LMAP_BLOCK) && !lbk_vctx_has_section(&ctx, LBK_SECTION_LMAP))
        vreport_at(&ctx, 117, 0, LBK_HDR_REQUIRED_FEATURES, "required feature LMAP_BLOCK is set but there is no LMAP");

    /* Pass 1, file order: checksums of every usable section, known or not. */
    uint8_t checksum_ok[LBK_MAX_SECTIONS] = {0};
    uint64_t unlimited = UINT64_MAX;
    for (uint32_t i = 0; i < fr->count && !ctx.stop; i++) {
        if (!fr->usable[i]) continue;
        const lbk_section_info *s = &fr->sections[i];
        const uint8_t *sd;
        void *owned;
        uint32_t issue;
        lbk_section_info only_checksum = *s;
        only_checksum.compression = LBK_COMPRESSION_NONE; /* verify, do not decode yet */
        if (s->type == LBK_SECTION_LMAP && s->compression == LBK_COMPRESSION_NONE && !ctx.lmap_hits &&
            (!rd || lbk_reader_checksum_pending(rd, i))) {
            /* one pass over the lightmap: its checksum and the block tests of its texels */
            uint8_t *hits;
            uint64_t bits;
            if (lbk_lmap_hash_prescan(d + s->offset, (size_t)s->stored_size, &alloc, &hits, &bits) == s->checksum) {
                checksum_ok[i] = 1;
                if (rd) lbk_reader_set_verified(rd, i);
                ctx.lmap_hits = hits, ctx.lmap_hit_bits = bits;
            } else {
                lbk_dealloc(&alloc, hits);
                vreport_at(&ctx, 214, s->type, s->offset, "%s", load_message(214));
            }
            continue;
        }
        lbk_result r = rd ? lbk_reader_verify(rd, i, &issue)
                          : lbk_section_load(d, &only_checksum, &alloc, 0, &unlimited, &sd, &owned, &issue);
        if (r == LBK_OK) checksum_ok[i] = 1;
        else vreport_at(&ctx, issue, s->type, s->offset, "%s", load_message(issue));
    }
    check_dependencies(&ctx);

    /* Pass 2, dependency order: decode and run each section's validator. */
    uint64_t budget = options->max_decoded_bytes ? options->max_decoded_bytes : lbk_default_decode_cap(size);
    for (size_t k = 0; k < sizeof dependency_order / sizeof dependency_order[0] && !ctx.stop; k++) {
        uint32_t i;
        for (i = 0; i < fr->count; i++)
            if (fr->sections[i].type == dependency_order[k].type) break;
        if (i == fr->count || !checksum_ok[i]) continue;
        const lbk_section_info *s = &fr->sections[i];
        const uint8_t *sd;
        void *owned = NULL;
        uint32_t issue;
        if (rd) budget = lbk_reader_budget_left(rd);
        lbk_result r = rd ? lbk_reader_load(rd, i, &sd, &issue)
                          : lbk_section_load(d, s, &alloc, 1, &budget, &sd, &owned, &issue);
        if (r == LBK_ERR_OUT_OF_MEMORY) {
            result = r;
            goto done;
        }
        if (r != LBK_OK) {
            if (issue == 217)
                vreport_at(&ctx, 217, s->type, s->offset, "decoded_size %llu exceeds the remaining cap of %llu bytes",
                           (unsigned long long)s->decoded_size, (unsigned long long)budget);
            else
                vreport_at(&ctx, issue, s->type, s->offset, "%s", load_message(issue));
            continue;
        }
        ctx.section_type = s->type;
        ctx.section_offset = s->offset;
        ctx.section_compressed = s->compression != LBK_COMPRESSION_NONE;
        dependency_order[k].run(&ctx, sd, (size_t)s->decoded_size);
        ctx.section_type = 0;
        ctx.section_offset = 0;
        ctx.section_compressed = 0;
        lbk_dealloc(&alloc, owned);
    }

done:
    lbk_dealloc(&alloc, ctx.lmap_hits);
    lbk_dealloc(&alloc, (void *)ctx.lmap_page_width);
    lbk_dealloc(&alloc, (void *)ctx.lmap_page_height);
    lbk_dealloc(&alloc, ctx.objs_facts);
    lbk_dealloc(&alloc, ctx.dls_facts);
    lbk_dealloc(&alloc, fr);
    return result;
}

lbk_result lbk_validate_memory(const void *data, size_t size, const lbk_validate_options *caller_options,
                               lbk_issue_callback callback, void *user, lbk_validate_summary *summary)
{
    lbk_validate_summary local;
    if (!summary) summary = &local;
    memset(summary, 0, sizeof *summary);
    if (!data && size) return LBK_ERR_INVALID_ARGUMENT;
    lbk_validate_options options;
    lbk_result rc = LBK_SIZED_IN(&options, caller_options, lbk_validate_options, max_decoded_bytes);
    if (rc != LBK_OK) return rc;
    return validate_core(data, size, &options, callback, user, summary, NULL);
}

lbk_result lbk_reader_validate(lbk_reader *reader, lbk_issue_callback callback, void *user,
                               lbk_validate_summary *summary)
{
    lbk_validate_summary local;
    if (!summary) summary = &local;
    memset(summary, 0, sizeof *summary);
    if (!reader) return LBK_ERR_INVALID_ARGUMENT;
    size_t size;
    const uint8_t *d = lbk_reader_bytes(reader, &size);
    lbk_validate_options options;
    memset(&options, 0, sizeof options);
    return validate_core(d, size, &options, callback, user, summary, reader);
}

lbk_result lbk_validate_file(const char *path, const lbk_validate_options *options, lbk_issue_callback callback,
                             void *user, lbk_validate_summary *summary)
{
    if (summary) memset(summary, 0, sizeof *summary);
    if (!path) return LBK_ERR_INVALID_ARGUMENT;
    const uint8_t *data;
    size_t size;
    lbk_result r = lbk_map_file(path, &data, &size);
    if (r != LBK_OK) return r;
    r = lbk_validate_memory(data, size, options, callback, user, summary);
    lbk_unmap_file(data, size);
    return r;
}
