/* The plan file of a distributed bake (tools/common/bake_plan.h). */
#include "tools/common/bake_plan.h"

#include <cjson/cJSON.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <xxhash.h>

#include "tools/common/file_util.h"

uint64_t tl_plan_hash(const tl_plan *p)
{
    XXH64_state_t *st = XXH64_createState();
    if (!st) return 0;
    XXH64_reset(st, 0);
    char head[96];
    int n = snprintf(head, sizeof head, "lbk-plan 2\n%016" PRIx64 "\n%u\n", p->scene_hash, p->units);
    XXH64_update(st, head, (size_t)n);
    for (size_t i = 0; i < p->input_count; i++) {
        const tl_plan_input *f = &p->inputs[i];
        char line[320];
        n = snprintf(line, sizeof line, "%.255s\n%.7s %" PRIu64 " %016" PRIx64 "\n", f->path, f->role, f->bytes, f->xxh3);
        XXH64_update(st, line, (size_t)n);
    }
    for (int i = 0; i < p->option_count; i++) XXH64_update(st, p->options[i], strlen(p->options[i]) + 1);
    uint64_t h = XXH64_digest(st);
    XXH64_freeState(st);
    return h ? h : 1; /* 0 means "no plan" to lbk_bake_part_check */
}

int tl_file_hash(const char *path, uint64_t *hash, char err[TL_ERR_LEN])
{
    void *data = NULL;
    size_t size = 0;
    if (tl_read_file(path, &data, &size, err)) return -1;
    *hash = XXH64(data, size, 0);
    free(data);
    return 0;
}

static char *hex64(uint64_t v, char buf[17])
{
    snprintf(buf, 17, "%016" PRIx64, v);
    return buf;
}

int tl_plan_write(const tl_plan *p, const char *path, char err[TL_ERR_LEN])
{
    cJSON *root = cJSON_CreateObject();
    char h[17];
    int ok = root != NULL;
    ok = ok && cJSON_AddStringToObject(root, "format", "lbk-plan");
    ok = ok && cJSON_AddNumberToObject(root, "version", 2);
    ok = ok && cJSON_AddStringToObject(root, "scene", p->scene);
    ok = ok && cJSON_AddStringToObject(root, "scene_xxh64", hex64(p->scene_hash, h));
    cJSON *files = ok ? cJSON_AddArrayToObject(root, "inputs") : NULL;
    ok = ok && files;
    for (size_t i = 0; ok && i < p->input_count; i++) {
        cJSON *f = cJSON_CreateObject();
        ok = f && cJSON_AddItemToArray(files, f);
        ok = ok && cJSON_AddStringToObject(f, "path", p->inputs[i].path);
        ok = ok && cJSON_AddStringToObject(f, "role", p->inputs[i].role);
        ok = ok && cJSON_AddNumberToObject(f, "bytes", (double)p->inputs[i].bytes);
        ok = ok && cJSON_AddStringToObject(f, "xxh3", hex64(p->inputs[i].xxh3, h));
    }
    ok = ok && cJSON_AddStringToObject(root, "output", p->output);
    ok = ok && cJSON_AddNumberToObject(root, "units", p->units);
    cJSON *opts = ok ? cJSON_AddArrayToObject(root, "options") : NULL;
    ok = ok && opts;
    for (int i = 0; ok && i < p->option_count; i++) {
        cJSON *s = cJSON_CreateString(p->options[i]);
        ok = s && cJSON_AddItemToArray(opts, s);
    }
    ok = ok && cJSON_AddStringToObject(root, "plan_hash", hex64(tl_plan_hash(p), h));
    char *text = ok ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!text) {
        snprintf(err, TL_ERR_LEN, "out of memory");
        return -1;
    }
    int r = tl_write_text(path, text, err);
    cJSON_free(text);
    return r;
}

static int parse_hex64(const cJSON *j, uint64_t *v)
{
    if (!cJSON_IsString(j) || strlen(j->valuestring) != 16) return 0;
    char *end;
    *v = strtoull(j->valuestring, &end, 16);
    return *end == 0;
}

/* The plan's "inputs": [{path, role, bytes, xxh3}, ...] (strings must fit, sizes be integers). */
static int read_inputs(const cJSON *files, tl_plan *p)
{
    if (!cJSON_IsArray(files)) return 0;
    int n = cJSON_GetArraySize(files);
    if (n < 1 || n > TL_PLAN_MAX_INPUTS) return 0;
    p->inputs = calloc((size_t)n, sizeof *p->inputs);
    if (!p->inputs) return 0;
    const cJSON *f;
    cJSON_ArrayForEach(f, files)
    {
        const cJSON *path = cJSON_GetObjectItemCaseSensitive(f, "path");
        const cJSON *role = cJSON_GetObjectItemCaseSensitive(f, "role");
        const cJSON *bytes = cJSON_GetObjectItemCaseSensitive(f, "bytes");
        tl_plan_input *in = &p->inputs[p->input_count];
        if (!cJSON_IsString(path) || strlen(path->valuestring) >= sizeof in->path || !cJSON_IsString(role) ||
            strlen(role->valuestring) >= sizeof in->role || !cJSON_IsNumber(bytes) || !(bytes->valuedouble >= 0) ||
            bytes->valuedouble > 9007199254740992.0 || bytes->valuedouble != (double)(uint64_t)bytes->valuedouble ||
            !parse_hex64(cJSON_GetObjectItemCaseSensitive(f, "xxh3"), &in->xxh3))
            return 0;
        memcpy(in->path, path->valuestring, strlen(path->valuestring) + 1);
        memcpy(in->role, role->valuestring, strlen(role->valuestring) + 1);
        in->bytes = (uint64_t)bytes->valuedouble;
        p->input_count++;
    }
    return 1;
}

int tl_plan_read(const char *path, tl_plan *p, char err[TL_ERR_LEN])
{
    memset(p, 0, sizeof *p);
    void *data = NULL;
    size_t size = 0;
    if (tl_read_file(path, &data, &size, err)) return -1;
    cJSON *root = size < (1u << 20) ? cJSON_ParseWithLength(data, size) : NULL;
    free(data);
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
    const cJSON *ver = cJSON_GetObjectItemCaseSensitive(root, "version");
    const cJSON *scene = cJSON_GetObjectItemCaseSensitive(root, "scene");
    const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output");
    const cJSON *units = cJSON_GetObjectItemCaseSensitive(root, "units");
    const cJSON *opts = cJSON_GetObjectItemCaseSensitive(root, "options");
    uint64_t stored = 0;
    int ok = root && cJSON_IsString(fmt) && !strcmp(fmt->valuestring, "lbk-plan") && cJSON_IsNumber(ver) &&
             ver->valuedouble == 2 && cJSON_IsString(scene) && cJSON_IsString(out) && cJSON_IsNumber(units) &&
             units->valuedouble >= 1 && units->valuedouble <= 65536 && units->valuedouble == (double)(int)units->valuedouble &&
             cJSON_IsArray(opts) && cJSON_GetArraySize(opts) <= TL_PLAN_MAX_OPTIONS &&
             parse_hex64(cJSON_GetObjectItemCaseSensitive(root, "scene_xxh64"), &p->scene_hash) &&
             parse_hex64(cJSON_GetObjectItemCaseSensitive(root, "plan_hash"), &stored);
    if (ok) {
        p->scene = strdup(scene->valuestring);
        p->output = strdup(out->valuestring);
        p->units = (uint32_t)units->valuedouble;
        ok = p->scene && p->output;
        const cJSON *o;
        cJSON_ArrayForEach(o, opts)
        {
            if (!ok || !cJSON_IsString(o)) { ok = 0; break; }
            if (!(p->options[p->option_count++] = strdup(o->valuestring))) ok = 0;
        }
        if (ok) ok = read_inputs(cJSON_GetObjectItemCaseSensitive(root, "inputs"), p);
    }
    cJSON_Delete(root);
    if (!ok) {
        tl_plan_free(p);
        snprintf(err, TL_ERR_LEN, "%s: not an lbk plan (format lbk-plan, version 2)", path);
        return -1;
    }
    p->hash = tl_plan_hash(p);
    if (p->hash != stored) {
        tl_plan_free(p);
        snprintf(err, TL_ERR_LEN, "%s: the plan was edited (its plan_hash does not match its contents)", path);
        return -1;
    }
    return 0;
}

void tl_plan_free(tl_plan *p)
{
    free(p->scene);
    free(p->output);
    free(p->inputs);
    for (int i = 0; i < p->option_count; i++) free(p->options[i]);
    memset(p, 0, sizeof *p);
}
