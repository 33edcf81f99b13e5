/* lbk inspect's report and JSON document (tools/inspect/report.h). */
#include "tools/inspect/report.h"

#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "tools/common/bake_data.h"

static void add_stats(inspect_stats *sum, const inspect_stats *s)
{
    sum->lm_texels += s->lm_texels;
    sum->lm_pages += s->lm_pages;
    sum->glg_probes += s->glg_probes;
    sum->glg_tetrahedra += s->glg_tetrahedra;
    sum->llg_grids += s->llg_grids;
    sum->llg_probes += s->llg_probes;
    sum->llg_vertices += s->llg_vertices;
    sum->octp_probes += s->octp_probes;
    sum->objects += s->objects;
    sum->dls_light_sets += s->dls_light_sets;
    sum->dls_sets += s->dls_sets;
    sum->dls_clusters += s->dls_clusters;
    sum->dls_payload_bytes += s->dls_payload_bytes;
    sum->dls_ancillary_bytes += s->dls_ancillary_bytes;
    sum->doors += s->doors;
    sum->door_states += s->door_states;
    if (s->terr_present) {
        sum->terr_present = 1, sum->terr_denoised = s->terr_denoised;
        sum->terr_texels = s->terr_texels, sum->terr_estimated = s->terr_estimated;
        sum->terr_median = s->terr_median, sum->terr_p90 = s->terr_p90;
    }
}

static int is_dynamic(uint32_t type) { return type == LBK_SECTION_DLS || type == LBK_SECTION_DOOR; }

void tl_inspect_scan(lbk_reader *reader, const char *path, tl_inspect_report *r)
{
    memset(r, 0, sizeof *r);
    r->path = path;
    r->h = lbk_reader_header(reader);
    r->count = lbk_reader_section_count(reader);
    r->header_bytes = LBK_HEADER_SIZE;
    r->table_bytes = (uint64_t)LBK_SECTION_ENTRY_SIZE * r->count;
    uint64_t sections_disk = 0, prev_end = r->header_bytes + r->table_bytes;
    for (uint32_t i = 0; i < r->count; i++) {
        tl_inspect_section *s = &r->rows[i];
        lbk_reader_section_get(reader, i, &s->info);
        lbk_fourcc_string(s->info.type, s->type);
        inspect_describe_fn fn = inspect_describer(s->info.type);
        s->known = fn != NULL;
        const void *data;
        size_t size;
        s->error = lbk_reader_section_data(reader, i, &data, &size);
        s->readable = s->error == LBK_OK;
        if (s->readable && fn) fn(data, size, &s->st);
        if (!s->readable) r->any_unreadable = 1;
        sections_disk += s->info.stored_size;
        /* the gaps the alignment rule left, measured (not derived from the file size) */
        if (s->info.offset > prev_end) r->padding_bytes += s->info.offset - prev_end;
        prev_end = s->info.offset + s->info.stored_size;
        r->decoded_total += s->info.decoded_size;
        r->gpu_total += s->st.gpu_bytes;
        if (is_dynamic(s->info.type)) r->memory_with_dls += s->st.gpu_bytes;
        else r->memory_without_dls += s->st.gpu_bytes;
        add_stats(&r->level, &s->st);
    }
    r->memory_with_dls += r->memory_without_dls;
    if (r->h->file_size > prev_end) r->padding_bytes += r->h->file_size - prev_end;
    r->disk_total = r->header_bytes + r->table_bytes + sections_disk + r->padding_bytes;
}

char *tl_inspect_json(const tl_inspect_report *r)
{
    cJSON *doc = cJSON_CreateObject();
    if (!doc) return NULL;
    cJSON_AddStringToObject(doc, "schema", "lbk-inspect/1");
    cJSON_AddStringToObject(doc, "file", r->path);
    cJSON_AddNumberToObject(doc, "file_size", (double)r->h->file_size);
    cJSON *ver = cJSON_AddObjectToObject(doc, "version");
    if (ver) {
        cJSON_AddNumberToObject(ver, "major", r->h->version_major);
        cJSON_AddNumberToObject(ver, "minor", r->h->version_minor);
    }
    cJSON_AddNumberToObject(doc, "section_alignment", r->h->section_alignment);
    cJSON_AddNumberToObject(doc, "required_features", r->h->required_features);
    cJSON_AddNumberToObject(doc, "header_bytes", (double)r->header_bytes);
    cJSON_AddNumberToObject(doc, "table_bytes", (double)r->table_bytes);
    cJSON_AddNumberToObject(doc, "padding_bytes", (double)r->padding_bytes);
    cJSON *secs = cJSON_AddArrayToObject(doc, "sections");
    for (uint32_t i = 0; secs && i < r->count; i++) {
        const tl_inspect_section *s = &r->rows[i];
        cJSON *j = cJSON_CreateObject();
        if (!j || !cJSON_AddItemToArray(secs, j)) {
            cJSON_Delete(j);
            break;
        }
        cJSON_AddStringToObject(j, "type", s->type);
        cJSON_AddBoolToObject(j, "required", (s->info.flags & LBK_SECTION_FLAG_REQUIRED) != 0);
        cJSON_AddStringToObject(j, "compression", s->info.compression ? "zstd" : "none");
        cJSON_AddNumberToObject(j, "offset", (double)s->info.offset);
        cJSON_AddNumberToObject(j, "disk_bytes", (double)s->info.stored_size);
        cJSON_AddNumberToObject(j, "decoded_bytes", (double)s->info.decoded_size);
        cJSON_AddNumberToObject(j, "gpu_bytes", (double)s->st.gpu_bytes);
        cJSON_AddBoolToObject(j, "known", s->known);
        cJSON_AddBoolToObject(j, "readable", s->readable);
        cJSON_AddBoolToObject(j, "parsed", s->st.parsed);
        if (!s->readable) cJSON_AddStringToObject(j, "error", lbk_result_name(s->error));
        cJSON_AddStringToObject(j, "detail", s->st.detail);
    }
    cJSON *tot = cJSON_AddObjectToObject(doc, "totals");
    if (tot) {
        cJSON_AddNumberToObject(tot, "disk_bytes", (double)r->disk_total);
        cJSON_AddNumberToObject(tot, "decoded_bytes", (double)r->decoded_total);
        cJSON_AddNumberToObject(tot, "gpu_bytes", (double)r->gpu_total);
        cJSON_AddBoolToObject(tot, "disk_matches_file_size", r->disk_total == r->h->file_size);
    }
    const inspect_stats *l = &r->level;
    cJSON *lv = cJSON_AddObjectToObject(doc, "level");
    if (lv) {
        cJSON_AddNumberToObject(lv, "lm_texels", (double)l->lm_texels);
        cJSON_AddNumberToObject(lv, "lm_pages", (double)l->lm_pages);
        uint64_t lm_gpu = 0;
        for (uint32_t i = 0; i < r->count; i++)
            if (r->rows[i].info.type == LBK_SECTION_LMAP) lm_gpu = r->rows[i].st.gpu_bytes;
        cJSON_AddNumberToObject(lv, "lm_gpu_bytes_per_texel", l->lm_texels ? (double)lm_gpu / (double)l->lm_texels : 0.0);
        cJSON_AddNumberToObject(lv, "llg_probes", (double)l->llg_probes);
        cJSON_AddNumberToObject(lv, "llg_grids", (double)l->llg_grids);
        cJSON_AddNumberToObject(lv, "llg_vertices", (double)l->llg_vertices);
        cJSON_AddNumberToObject(lv, "glg_probes", (double)l->glg_probes);
        cJSON_AddNumberToObject(lv, "glg_tetrahedra", (double)l->glg_tetrahedra);
        cJSON_AddNumberToObject(lv, "octp_probes", (double)l->octp_probes);
        cJSON_AddNumberToObject(lv, "objects", (double)l->objects);
        cJSON_AddNumberToObject(lv, "dls_light_sets", (double)l->dls_light_sets);
        cJSON_AddNumberToObject(lv, "dls_sets", (double)l->dls_sets);
        cJSON_AddNumberToObject(lv, "dls_clusters", (double)l->dls_clusters);
        cJSON_AddNumberToObject(lv, "dls_payload_bytes", (double)l->dls_payload_bytes);
        cJSON_AddNumberToObject(lv, "dls_ancillary_bytes", (double)l->dls_ancillary_bytes);
        cJSON_AddNumberToObject(lv, "doors", (double)l->doors);
        cJSON_AddNumberToObject(lv, "door_states", (double)l->door_states);
        cJSON_AddNumberToObject(lv, "memory_without_dls_bytes", (double)r->memory_without_dls);
        cJSON_AddNumberToObject(lv, "memory_with_dls_bytes", (double)r->memory_with_dls);
        /* the per-texel error map (TERR, format 1.4): null without one (added within lbk-inspect/1) */
        if (!l->terr_present) cJSON_AddNullToObject(lv, "error_map");
        else {
            cJSON *em = cJSON_AddObjectToObject(lv, "error_map");
            if (em) {
                cJSON_AddNumberToObject(em, "texels", (double)l->terr_texels);
                cJSON_AddNumberToObject(em, "texels_with_estimate", (double)l->terr_estimated);
                cJSON_AddNumberToObject(em, "median_rel_error", l->terr_median);
                cJSON_AddNumberToObject(em, "p90_rel_error", l->terr_p90);
                cJSON_AddBoolToObject(em, "before_denoising", l->terr_denoised);
            }
        }
    }
    if (r->memory) {
        cJSON *objs = cJSON_AddArrayToObject(doc, "objects");
        for (size_t i = 0; objs && i < r->memory->object_count; i++) {
            const tl_object_memory *o = &r->memory->objects[i];
            cJSON *j = cJSON_CreateObject();
            if (!j || !cJSON_AddItemToArray(objs, j)) {
                cJSON_Delete(j);
                break;
            }
            cJSON_AddStringToObject(j, "name", o->name);
            cJSON_AddStringToObject(j, "representation", lbk_representation_name(o->representation));
            cJSON_AddNumberToObject(j, "texels", (double)o->texels);
            cJSON_AddNumberToObject(j, "lightmap_bytes", (double)o->lightmap_bytes);
            cJSON_AddNumberToObject(j, "llg_probes", (double)o->llg_probes);
            cJSON_AddNumberToObject(j, "llg_vertices", (double)o->llg_vertices);
            cJSON_AddNumberToObject(j, "llg_bytes", (double)o->llg_bytes);
            cJSON_AddNumberToObject(j, "dls_entries", (double)o->dls_entries);
            cJSON_AddNumberToObject(j, "dls_bytes", (double)o->dls_bytes);
            cJSON_AddNumberToObject(j, "total_bytes", (double)o->total_bytes);
        }
        cJSON *sets = cJSON_AddArrayToObject(doc, "light_sets");
        for (size_t i = 0; sets && i < r->memory->set_count; i++) {
            const tl_set_memory *m = &r->memory->sets[i];
            cJSON *j = cJSON_CreateObject();
            if (!j || !cJSON_AddItemToArray(sets, j)) {
                cJSON_Delete(j);
                break;
            }
            static const char *const kinds[] = {"lights", "door_open", "door_closed", "combination"};
            cJSON_AddStringToObject(j, "name", m->name);
            cJSON_AddStringToObject(j, "kind", m->kind < 4 ? kinds[m->kind] : "unknown");
            cJSON_AddNumberToObject(j, "texel_entries", (double)m->entries[0]);
            cJSON_AddNumberToObject(j, "glg_entries", (double)m->entries[1]);
            cJSON_AddNumberToObject(j, "llg_entries", (double)m->entries[2]);
            cJSON_AddNumberToObject(j, "payload_bytes", (double)m->payload_bytes);
        }
        cJSON_AddNumberToObject(doc, "dls_unowned_bytes", (double)r->memory->dls_unowned_bytes);
    } else {
        cJSON_AddNullToObject(doc, "objects");
        cJSON_AddNullToObject(doc, "light_sets");
        cJSON_AddStringToObject(doc, "objects_error", r->memory_error ? r->memory_error : "");
    }
    if (r->budget) {
        cJSON *bj = cJSON_AddObjectToObject(doc, "budget");
        cJSON_AddStringToObject(bj, "name", r->budget->name);
        cJSON_AddNumberToObject(bj, "checked", (double)r->budget_result->checked);
        cJSON_AddBoolToObject(bj, "within", r->budget_result->violation_count == 0);
        cJSON *vs = cJSON_AddArrayToObject(bj, "violations");
        for (size_t i = 0; vs && i < r->budget_result->violation_count; i++) {
            const tl_budget_violation *v = &r->budget_result->violations[i];
            cJSON *j = cJSON_CreateObject();
            if (!j || !cJSON_AddItemToArray(vs, j)) {
                cJSON_Delete(j);
                break;
            }
            cJSON_AddStringToObject(j, "kind", tl_budget_kind_name(v->kind));
            cJSON_AddStringToObject(j, "name", v->name);
            cJSON_AddNumberToObject(j, "bytes", (double)v->bytes);
            cJSON_AddNumberToObject(j, "limit", (double)v->limit);
        }
    } else {
        cJSON_AddNullToObject(doc, "budget");
    }
    char *text = cJSON_Print(doc);
    cJSON_Delete(doc);
    return text;
}


int tl_inspect_file_json(const char *path, uint64_t max_memory, char **json)
{
    *json = NULL;
    lbk_read_options ro = LBK_READ_OPTIONS_INIT;
    ro.max_decoded_bytes = max_memory;
    lbk_reader *reader;
    if (lbk_reader_open_file(path, &ro, &reader) != LBK_OK) return -1;
    tl_inspect_report *r = malloc(sizeof *r); /* large (64 rows) */
    if (!r) {
        lbk_reader_close(reader);
        return -1;
    }
    tl_inspect_scan(reader, path, r);
    tl_bake bake;
    tl_level_memory mem;
    int have_mem = 0;
    char err[TL_ERR_LEN];
    if (tl_bake_open_file_capped(path, max_memory, &bake, err) == TL_OPEN_OK) {
        if (tl_level_memory_get(&bake, &mem) == 0) have_mem = 1, r->memory = &mem;
        else r->memory_error = "out of memory";
        tl_bake_close(&bake);
    } else {
        r->memory_error = "the file does not validate (run lbk validate)";
    }
    if (!r->any_unreadable) *json = tl_inspect_json(r);
    lbk_reader_close(reader);
    if (have_mem) tl_level_memory_free(&mem);
    free(r);
    return *json ? 0 : -1;
}
