/* Repacking with a profile. The pack is a pure function of (input bytes, profile, imported pages):
 * sections are decoded, optionally rewritten, and handed to the library writer, which lays them out
 * in canonical order; zstd at a fixed level is deterministic, so converting twice gives the same
 * bytes, and converting a pack again with the same profile reproduces it. */
#include "lbk/error_map.h"
#include "tools/convert/convert.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tools/common/bake_data.h"
#include "tools/common/error_util.h"
#include "tools/convert/lmap_layout.h"
#include "lbk/meta.h"
#include "lbk/validate.h"

typedef struct first_issue {
    int have;
    lbk_issue issue;
} first_issue;

static int keep_first_error(void *user, const lbk_issue *issue)
{
    first_issue *f = user;
    if (!f->have && issue->severity != LBK_SEVERITY_WARNING) {
        f->issue = *issue;
        f->have = 1;
    }
    return 0;
}

/* Validates bytes (through the reader when there is one, so each section is decoded once); on
 * failure fills err with the first error. */
static int validate_bytes(const void *data, size_t size, lbk_reader *reader, const char *what, char err[TL_ERR_LEN])
{
    first_issue f = {0};
    lbk_validate_summary sum = {0};
    lbk_result r = reader ? lbk_reader_validate(reader, keep_first_error, &f, &sum)
                          : lbk_validate_memory(data, size, NULL, keep_first_error, &f, &sum);
    if (r != LBK_OK) {
        snprintf(err, TL_ERR_LEN, "%s: validation could not run (%s)", what, lbk_result_name(r));
        return -1;
    }
    if (sum.fatal || sum.errors) {
        char t[5];
        lbk_fourcc_string(f.issue.section_type, t);
        snprintf(err, TL_ERR_LEN, "%s is invalid: %u error(s); first: #%u in %s at byte %llu: %s", what,
                 sum.fatal + sum.errors, f.issue.id, f.issue.section_type ? t : "header",
                 (unsigned long long)f.issue.offset, f.issue.message);
        return -1;
    }
    return 0;
}

/* The per-texel error map (spec §18) follows LMAP's texels when pages are widened: each code
 * moves with its texel, the new padding texels get 0 (no estimate). */
static int terr_remap_texels(const void *data, size_t size, const tl_texel_remap *remap, void **out, size_t *out_size,
                             char err[TL_ERR_LEN])
{
    lbk_terr_view v;
    if (lbk_terr_open(data, size, &v) != LBK_OK || v.texel_count != remap->old_total)
        return tl_fail(err, TL_CONVERT_BAD_INPUT, "TERR does not match the lightmap's texels");
    uint8_t *codes = calloc((size_t)remap->new_total + 1, 1);
    if (!codes) return tl_fail(err, TL_CONVERT_INTERNAL, "out of memory");
    for (uint64_t i = 0; i < v.texel_count; i++) {
        uint64_t j;
        if (v.codes[i] && tl_texel_remap_apply(remap, i, &j) == 0 && j < remap->new_total) codes[j] = v.codes[i];
    }
    void *built = NULL;
    lbk_result r = lbk_terr_build(v.flags, codes, remap->new_total, NULL, &built, out_size);
    free(codes);
    if (r != LBK_OK) return tl_fail(err, TL_CONVERT_INTERNAL, "TERR: %s", lbk_result_message(r));
    /* the caller frees with free(): lbk_terr_build used the default allocator (malloc) */
    *out = built;
    return TL_CONVERT_OK;
}

/* META of a pack that keeps it: the input's keys plus convert.profile and convert.profile_hash
 * (spec/container.md §6.2), replacing those of an earlier convert, so converting again with the
 * same profile gives the same bytes. */
static int meta_with_profile(const void *data, size_t size, const tl_profile *p, void **out, size_t *out_size,
                             char err[TL_ERR_LEN])
{
    lbk_meta_view v;
    if (lbk_meta_open(data, size, &v) != LBK_OK) return tl_fail(err, TL_CONVERT_BAD_INPUT, "input META unreadable");
    lbk_meta_pair *pairs = calloc((size_t)v.entry_count + 2, sizeof *pairs);
    char **owned = calloc(2 * (size_t)v.entry_count + 1, sizeof *owned);
    char hash[17];
    lbk_meta_hash_hex(p->text_hash, hash);
    size_t n = 0, k = 0;
    int st = TL_CONVERT_INTERNAL;
    if (!pairs || !owned) goto done;
    for (uint32_t i = 0; i < v.entry_count; i++) {
        lbk_string key, val;
        lbk_meta_entry_get(&v, i, &key, &val);
        if ((key.size == 15 && !memcmp(key.data, "convert.profile", 15)) ||
            (key.size == 20 && !memcmp(key.data, "convert.profile_hash", 20)))
            continue;
        char *ks = strndup(key.data, key.size), *vs = strndup(val.data, val.size);
        owned[k++] = ks, owned[k++] = vs;
        if (!ks || !vs) goto done;
        pairs[n++] = (lbk_meta_pair){ks, vs};
    }
    pairs[n++] = (lbk_meta_pair){"convert.profile", p->name};
    pairs[n++] = (lbk_meta_pair){"convert.profile_hash", hash};
    st = lbk_meta_build(pairs, n, NULL, out, out_size) == LBK_OK ? TL_CONVERT_OK : TL_CONVERT_INTERNAL;
    if (st != TL_CONVERT_OK) tl_fail(err, st, "META with the profile could not be built");
done:
    for (size_t i = 0; i < k; i++) free(owned[i]);
    free(owned);
    free(pairs);
    if (st == TL_CONVERT_INTERNAL && !*out) snprintf(err, TL_ERR_LEN, "out of memory");
    return st;
}

/* The pack's lightmap against the input's: 1 computed, 0 nothing to compare (no lightmap), -1 an
 * error (err). Both are opened again through the tools' loader, which decodes block pages with
 * the same decoders a reader of the pack uses. */
static int pack_error(const void *in, size_t in_size, const void *pack, size_t pack_size, tl_pack_error *out,
                      char err[TL_ERR_LEN])
{
    memset(out, 0, sizeof *out);
    tl_bake a, p;
    memset(&a, 0, sizeof a), memset(&p, 0, sizeof p);
    int rc = -1;
    if (tl_bake_open_memory(in, in_size, &a, err) != TL_OPEN_OK || tl_bake_open_memory(pack, pack_size, &p, err) != TL_OPEN_OK)
        goto done;
    rc = 0;
    if (a.has_lmap && a.has_objs && p.has_lmap && p.has_objs) rc = tl_pack_error_compute(&a, &p, out, err) ? -1 : 1;
done:
    if (a.bytes) tl_bake_close(&a);
    if (p.bytes) tl_bake_close(&p);
    return rc;
}

tl_convert_status tl_convert_memory(const void *in, size_t in_size, const tl_convert_options *opt, void **out,
                                    size_t *out_size, tl_convert_report *report, char err[TL_ERR_LEN])
{
    *out = NULL;
    *out_size = 0;
    tl_convert_report local;
    if (!report) report = &local;
    memset(report, 0, sizeof *report);
    report->in_size = in_size;
    const tl_profile *p = opt->profile;

    lbk_reader *rd = NULL;
    lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    ro.max_decoded_bytes = opt->max_decoded_bytes;
    lbk_result r = lbk_reader_open_memory(in, in_size, &ro, &rd);
    if (r != LBK_OK) {
        if (validate_bytes(in, in_size, NULL, "input", err)) return TL_CONVERT_BAD_INPUT;
        return tl_fail(err, TL_CONVERT_BAD_INPUT, "input: %s", lbk_result_message(r));
    }
    if (validate_bytes(in, in_size, rd, "input", err)) {
        lbk_reader_close(rd);
        return TL_CONVERT_BAD_INPUT;
    }

    lbk_write_options wo = LBK_WRITE_OPTIONS_INIT;
    wo.section_alignment = p->alignment;
    lbk_writer *w = NULL;
    r = lbk_writer_open(&wo, &w);
    if (r != LBK_OK) {
        lbk_reader_close(rd);
        return tl_fail(err, TL_CONVERT_INTERNAL, "writer: %s", lbk_result_message(r));
    }

    tl_convert_status st = TL_CONVERT_OK;
    tl_texel_remap remap;
    memset(&remap, 0, sizeof remap);
    int have_remap = 0;
    uint32_t n = lbk_reader_section_count(rd);
    const void *objs = NULL; /* OBJS precedes LMAP (canonical order): which texels objects use */
    size_t objs_size = 0;
    for (uint32_t i = 0; i < n && st == TL_CONVERT_OK; i++) {
        lbk_section_info si;
        const void *data = NULL;
        size_t size = 0;
        if ((r = lbk_reader_section_get(rd, i, &si)) != LBK_OK || (r = lbk_reader_section_data(rd, i, &data, &size)) != LBK_OK) {
            st = tl_fail(err, TL_CONVERT_BAD_INPUT, "input section %u: %s", i, lbk_result_message(r));
            break;
        }
        if (si.type == LBK_SECTION_OBJS) objs = data, objs_size = size;
        tl_convert_section *cs = &report->sections[report->section_count++];
        cs->type = si.type;
        cs->in_stored = si.stored_size;
        cs->in_decoded = si.decoded_size;
        tl_section_rule rule = tl_profile_rule(p, si.type);
        if (rule.ship == TL_SHIP_DROP) {
            cs->dropped = 1;
            continue;
        }
        void *rewritten = NULL;
        size_t rewritten_size = 0;
        int ls = TL_CONVERT_OK;
        if (si.type == LBK_SECTION_LMAP) {
            tl_lmap_layout_options lo = {p->lmap_row_pitch_alignment, p->lmap_page_alignment, opt->from_exr_dir,
                                         {p->lmap_format[0], p->lmap_format[1]}, objs, objs_size,
                                         &report->encode_seconds, p->lmap_max_page};
            uint32_t imported = 0;
            tl_texel_remap_free(&remap);
            ls = tl_lmap_rewrite(data, size, &lo, &rewritten, &rewritten_size, &imported, &remap, err);
            report->pages_imported = imported;
            have_remap = ls == TL_CONVERT_OK;
        } else if (si.type == LBK_SECTION_DLS && have_remap && !remap.identity) {
            ls = tl_dls_remap_texels(data, size, &remap, &rewritten, &rewritten_size, err);
        } else if (si.type == LBK_SECTION_TERR && have_remap && !remap.identity) {
            ls = terr_remap_texels(data, size, &remap, &rewritten, &rewritten_size, err);
        } else if (si.type == LBK_SECTION_META) {
            ls = meta_with_profile(data, size, p, &rewritten, &rewritten_size, err);
        }
        if (ls != TL_CONVERT_OK) {
            st = (tl_convert_status)ls;
            break;
        }
        if (rewritten) {
            cs->relaid = 1;
            data = rewritten;
            size = rewritten_size;
        }
        lbk_section_options so = LBK_SECTION_OPTIONS_INIT;
        so.flags = si.flags;
        so.compression = rule.compression;
        so.zstd_level = rule.zstd_level;
        r = lbk_writer_section_add(w, si.type, data, size, &so);
        free(rewritten);
        if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_INTERNAL, "writing section %u: %s", i, lbk_result_message(r));
    }
    if (st == TL_CONVERT_OK && opt->from_exr_dir && report->pages_imported == 0)
        st = tl_fail(err, TL_CONVERT_BAD_EXR, "--from-exr %.160s: no page_NNN.exr for any lightmap page of the input",
                  opt->from_exr_dir);

    void *bytes = NULL;
    size_t bytes_size = 0;
    if (st == TL_CONVERT_OK) {
        r = lbk_writer_to_memory(w, &bytes, &bytes_size);
        if (r != LBK_OK) st = tl_fail(err, TL_CONVERT_INTERNAL, "serialising the pack: %s", lbk_result_message(r));
    }
    lbk_writer_close(w);
    lbk_reader_close(rd);
    tl_texel_remap_free(&remap);
    if (st != TL_CONVERT_OK) {
        lbk_free(NULL, bytes);
        return st;
    }
    /* Re-read the output to fill in the stored sizes, and refuse to hand out an invalid pack. */
    if (validate_bytes(bytes, bytes_size, NULL, "output", err)) {
        lbk_free(NULL, bytes);
        return TL_CONVERT_INTERNAL;
    }
    lbk_reader *ord = NULL;
    if (lbk_reader_open_memory(bytes, bytes_size, NULL, &ord) == LBK_OK) {
        for (uint32_t i = 0; i < report->section_count; i++) {
            tl_convert_section *cs = &report->sections[i];
            uint32_t idx;
            lbk_section_info si;
            if (cs->dropped || lbk_reader_section_find(ord, cs->type, &idx) != LBK_OK ||
                lbk_reader_section_get(ord, idx, &si) != LBK_OK)
                continue;
            cs->out_stored = si.stored_size;
            cs->out_decoded = si.decoded_size;
            cs->compression = si.compression;
        }
        lbk_reader_close(ord);
    }
    if (opt->pack_error && !opt->from_exr_dir) {
        /* a measure, not the product: when it cannot be made, the pack still ships and says why */
        const int pe = pack_error(in, in_size, bytes, bytes_size, opt->pack_error, report->pack_error_skipped);
        report->pack_error_computed = pe > 0;
        if (pe >= 0) report->pack_error_skipped[0] = 0;
    }
    /* lbk_free(NULL, …) is free(); hand the caller a malloc'ed buffer. */
    *out = bytes;
    *out_size = bytes_size;
    report->out_size = bytes_size;
    return TL_CONVERT_OK;
}
