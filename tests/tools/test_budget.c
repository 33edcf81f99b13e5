/* Memory budgets (lbk inspect --budget, tools/inspect/budget.h) and per-object memory
 * (tools/inspect/memory.h) on a real bake of two rooms whose lamp is a dynamic light set
 * (support/diff_scenes.h): the lamp's DLS entries are charged to the objects of its room and to
 * none of the sky-lit room's; a budget exactly at a level's total, a section, an object or the
 * light set passes, one byte less fails and names that item (exit 1). And the budget file
 * format: sizes with units, strict parsing with line numbers. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "lbk/bake.h"
#include "support/diff_scenes.h"
#include "tools/common/file_util.h"
#include "tools/inspect/budget.h"
#include "tools/inspect/describe.h"
#include "tools/inspect/memory.h"

static char dir[64], lbk_path[128];
static tl_bake bake;
static tl_level_memory mem;

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/lbk-budget-XXXXXX");
    if (!mkdtemp(dir)) return -1;
    snprintf(lbk_path, sizeof lbk_path, "%s/rooms.lbk", dir);
    ds_variant v = DS_BASE;
    v.lamp_set = "lamp";
    ds_store st;
    lbk_bake_scene sc;
    ds_build(&v, &st, &sc);
    lbk_bake_desc d = {0};
    d.seed = 1;
    d.max_samples = 64;
    lbk_bake_output *out;
    if (lbk_bake_from_scene(&sc, &d, &out) != LBK_OK) return -1;
    ds_free(&st);
    if (lbk_bake_output_write_file(out, lbk_path) != LBK_OK) return -1;
    lbk_bake_output_free(out);
    char err[TL_ERR_LEN];
    if (tl_bake_open_file(lbk_path, &bake, err) != TL_OPEN_OK) return -1;
    return tl_level_memory_get(&bake, &mem);
}

static int teardown(void **state)
{
    (void)state;
    tl_level_memory_free(&mem);
    tl_bake_close(&bake);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static const tl_object_memory *object(const char *name)
{
    for (size_t i = 0; i < mem.object_count; i++)
        if (!strcmp(mem.objects[i].name, name)) return &mem.objects[i];
    fail_msg("no object %s", name);
    return NULL;
}

/* Per object: texels × 8 bytes, the lamp's entries on B's objects only, totals add up. */
static void test_object_memory(void **state)
{
    (void)state;
    assert_int_equal(mem.object_count, DS_OBJECTS);
    assert_int_equal(mem.set_count, 1);
    assert_string_equal(mem.sets[0].name, "lamp");
    uint64_t charged = 0;
    for (size_t i = 0; i < mem.object_count; i++) {
        const tl_object_memory *o = &mem.objects[i];
        lbk_object ob;
        assert_int_equal(lbk_objects_get(&bake.objs, (uint32_t)i, &ob), LBK_OK);
        assert_int_equal(o->representation, LBK_REPRESENTATION_LIGHTMAP);
        assert_int_equal(o->texels, (uint64_t)ob.rect_w * ob.rect_h);
        assert_int_equal(o->lightmap_bytes, 8 * o->texels);
        assert_int_equal(o->dls_bytes, 8 * o->dls_entries);
        assert_int_equal(o->total_bytes, o->lightmap_bytes + o->dls_bytes);
        if (ds_in_room_a(o->name)) assert_int_equal(o->dls_entries, 0); /* the lamp cannot reach room A */
        else assert_true(o->dls_entries > o->texels / 2);               /* it lights most of room B */
        charged += o->dls_bytes;
    }
    /* every texel entry is on some object's rectangle or charged as unowned; probes are unowned */
    assert_int_equal(charged + mem.dls_unowned_bytes, mem.sets[0].payload_bytes);
    assert_int_equal(mem.sets[0].payload_bytes, 8 * mem.sets[0].entries[0] + 28 * (mem.sets[0].entries[1] + mem.sets[0].entries[2]));
}

static int inspect(const char *budget_file_text, const char *size_arg)
{
    char bpath[128], err[TL_ERR_LEN];
    snprintf(bpath, sizeof bpath, "%s/b.budget", dir);
    if (budget_file_text) assert_int_equal(tl_write_file_atomic(bpath, budget_file_text, strlen(budget_file_text), err), 0);
    char *argv[] = {"inspect", lbk_path, "--budget", budget_file_text ? bpath : (char *)size_arg, NULL};
    fflush(stdout);
    int saved = dup(1);
    freopen("/dev/null", "w", stdout);
    int rc = lbk_cmd_inspect(4, argv);
    fflush(stdout);
    dup2(saved, 1);
    close(saved);
    return rc;
}

/* The level's GPU bytes per section as lbk inspect counts them (the describers). */
static uint64_t level_numbers(uint32_t types[LBK_MAX_SECTIONS], uint64_t gpu[LBK_MAX_SECTIONS], uint32_t *n)
{
    *n = lbk_reader_section_count(bake.reader);
    uint64_t total = 0;
    for (uint32_t i = 0; i < *n; i++) {
        lbk_section_info si;
        const void *d;
        size_t size;
        lbk_reader_section_get(bake.reader, i, &si);
        assert_int_equal(lbk_reader_section_data(bake.reader, i, &d, &size), LBK_OK);
        inspect_stats st;
        memset(&st, 0, sizeof st);
        inspect_describe_fn fn = inspect_describer(si.type);
        if (fn) fn(d, size, &st);
        types[i] = si.type;
        gpu[i] = st.gpu_bytes;
        total += gpu[i];
    }
    return total;
}

static void at_and_over(const char *fmt, uint64_t bytes, const char *kind, const char *name)
{
    char text[256];
    snprintf(text, sizeof text, fmt, (unsigned long long)bytes);
    assert_int_equal(inspect(text, NULL), LBK_EXIT_OK);
    snprintf(text, sizeof text, fmt, (unsigned long long)(bytes - 1));
    assert_int_equal(inspect(text, NULL), LBK_EXIT_NEGATIVE);
    /* and the check names exactly that item */
    tl_budget b;
    char err[TL_ERR_LEN];
    assert_int_equal(tl_budget_parse(text, strlen(text), "t", &b, err), 0);
    uint32_t types[LBK_MAX_SECTIONS], n;
    uint64_t gpu[LBK_MAX_SECTIONS];
    const uint64_t total = level_numbers(types, gpu, &n);
    tl_budget_level lv = {total, types, gpu, n, &mem};
    tl_budget_result res;
    assert_int_equal(tl_budget_check(&b, &lv, &res), 0);
    {
        assert_int_equal(res.violation_count, 1);
        assert_string_equal(tl_budget_kind_name(res.violations[0].kind), kind);
        assert_string_equal(res.violations[0].name, name);
        assert_int_equal(res.violations[0].bytes, bytes);
        assert_int_equal(res.violations[0].limit, bytes - 1);
    }
    tl_budget_result_free(&res);
}

static void test_one_byte_over_fails(void **state)
{
    (void)state;
    uint32_t types[LBK_MAX_SECTIONS], n;
    uint64_t gpu[LBK_MAX_SECTIONS];
    const uint64_t total = level_numbers(types, gpu, &n);
    /* LMAP 8 B/texel + GLG + DLS */
    assert_true(total > 8 * bake.lmap.texel_count);
    char arg[32];
    snprintf(arg, sizeof arg, "%llu", (unsigned long long)total);
    assert_int_equal(inspect(NULL, arg), LBK_EXIT_OK);
    snprintf(arg, sizeof arg, "%llu", (unsigned long long)(total - 1));
    assert_int_equal(inspect(NULL, arg), LBK_EXIT_NEGATIVE);
    at_and_over("total = %llu\n", total, "total", "");

    at_and_over("[sections]\nLMAP = %llu\n", 8 * bake.lmap.texel_count, "section", "LMAP");
    const tl_object_memory *floor_b = object("B_floor");
    at_and_over("[objects]\n\"B_floor\" = %llu\n", floor_b->total_bytes, "object", "B_floor");
    at_and_over("[light_sets]\nlamp = %llu\n", mem.sets[0].payload_bytes, "light_set", "lamp");
    /* a default applies to every object: the largest one decides */
    uint64_t largest = 0;
    for (size_t i = 0; i < mem.object_count; i++)
        if (mem.objects[i].total_bytes > largest) largest = mem.objects[i].total_bytes;
    char text[128];
    snprintf(text, sizeof text, "[objects]\ndefault = %llu\n", (unsigned long long)largest);
    assert_int_equal(inspect(text, NULL), LBK_EXIT_OK);
    snprintf(text, sizeof text, "[objects]\ndefault = %llu\n", (unsigned long long)(largest - 1));
    assert_int_equal(inspect(text, NULL), LBK_EXIT_NEGATIVE);
}

static void test_budget_file_format(void **state)
{
    (void)state;
    uint64_t v;
    assert_int_equal(tl_budget_parse_size("64MiB", &v), 0), assert_int_equal(v, 67108864);
    assert_int_equal(tl_budget_parse_size("1.5 kB", &v), 0), assert_int_equal(v, 1500);
    assert_int_equal(tl_budget_parse_size("2 GiB", &v), 0), assert_int_equal(v, (uint64_t)2 << 30);
    assert_int_equal(tl_budget_parse_size("12", &v), 0), assert_int_equal(v, 12);
    assert_int_equal(tl_budget_parse_size("12 B", &v), 0), assert_int_equal(v, 12);
    assert_int_equal(tl_budget_parse_size("1.5", &v), -1);   /* half a byte */
    assert_int_equal(tl_budget_parse_size("-3", &v), -1);
    assert_int_equal(tl_budget_parse_size("10 XB", &v), -1);
    assert_int_equal(tl_budget_parse_size("10 MB extra", &v), -1);
    tl_budget b;
    char err[TL_ERR_LEN];
    const char *good = "# ps5\nname = ps5-level\ntotal = 48 MiB   # all GPU memory\n[sections]\nLMAP = 32MiB\nGLG = 2MiB\n"
                       "default = 8MiB\n[objects]\ndefault = 4MiB\n\"Wall #3\" = 6MiB\n[light_sets]\ndefault = 1MiB\n";
    assert_int_equal(tl_budget_parse(good, strlen(good), "ps5.budget", &b, err), 0);
    assert_string_equal(b.name, "ps5-level");
    assert_int_equal(b.total, (uint64_t)48 << 20);
    assert_int_equal(b.section_count, 3);
    assert_int_equal(b.object_count, 2);
    assert_string_equal(b.objects[1].name, "Wall #3");
    static const struct {
        const char *text, *msg;
    } bad[] = {
        {"total = 1MiB\ntotl = 2\n", "ps5.budget:2: unknown key totl"},
        {"total = 1MiB\n[object]\n", "ps5.budget:2: unknown group [object]"},
        {"total = 1\ntotal = 2\n", "ps5.budget:2: total given twice"},
        {"[sections]\nLMAP = 1\nLMAP = 2\n", "ps5.budget:3: LMAP given twice"},
        {"[sections]\nLIGHTMAP = 1\n", "ps5.budget:2: LIGHTMAP is not a section type code"},
        {"total = lots\n", "ps5.budget:1: total: 'lots' is not a size"},
        {"# nothing\n", "ps5.budget: no limit at all"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(tl_budget_parse(bad[i].text, strlen(bad[i].text), "ps5.budget", &b, err), -1);
        if (strncmp(err, bad[i].msg, strlen(bad[i].msg))) fail_msg("got '%s', expected '%s...'", err, bad[i].msg);
    }
    /* the CLI: a bad budget is a usage error, a missing file too */
    assert_int_equal(inspect("total = lots\n", NULL), LBK_EXIT_USAGE);
    assert_int_equal(inspect(NULL, "/nonexistent/x.budget"), LBK_EXIT_USAGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_object_memory),
        cmocka_unit_test(test_one_byte_over_fails),
        cmocka_unit_test(test_budget_file_format),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
