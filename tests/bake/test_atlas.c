/* Atlas packing (bake/layout/atlas.h): placement rules, density, budget, pages, lightmap vertices. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake/layout/atlas.h"
#include "bake/layout/atlas_stats.h"
#include "bake/layout/texels.h"
#include "support/uv_scenes.h"

/* A unit-ish quad in the y = h plane as its own object. */
static uint32_t add_quad_object(bk_scene *s, const char *name, float x, float z, float sx, float sz, float h, int n)
{
    uint32_t o = uvs_object(s, name);
    float p0[3] = {x, h, z}, p1[3] = {x + sx, h, z}, p2[3] = {x + sx, h, z - sz}, p3[3] = {x, h, z - sz};
    uvs_quad(s, p0, p1, p2, p3, n, 0, NULL, 1.0f);
    return o;
}

/* A mixed scene: quads of many sizes, boxes, spheres. */
static void mixed_scene(bk_scene *s)
{
    uvs_init(s);
    for (int i = 0; i < 12; i++) {
        char name[32];
        snprintf(name, sizeof name, "q%d", i);
        add_quad_object(s, name, (float)i, 0, 0.3f + 0.45f * (float)(i % 5), 0.2f + 0.7f * (float)(i % 3), 0, 1 + i % 3);
    }
    for (int i = 0; i < 5; i++) {
        char name[32];
        snprintf(name, sizeof name, "box%d", i);
        uvs_object(s, name);
        float mn[3] = {(float)i * 3, 1, 0}, mx[3] = {(float)i * 3 + 0.5f + 0.6f * (float)i, 1.7f + 0.3f * (float)i, 1.2f};
        uvs_box(s, mn, mx, 1 + i % 2, i == 4, 0);
    }
    for (int i = 0; i < 3; i++) {
        char name[32];
        snprintf(name, sizeof name, "sphere%d", i);
        uvs_object(s, name);
        float c[3] = {(float)i * 4, 5, 0};
        uvs_sphere(s, c, 0.4f + 0.5f * (float)i, 16 + 8 * i, 8 + 4 * i, 0);
    }
    uvs_update_bounds(s);
}

/* Checks every layout rule of atlas.h against the atlas. */
static void check_layout(const bk_scene *s, const bk_atlas *a, int max_page)
{
    assert_true(a->padding >= 2);
    assert_int_equal(a->padding, 2 * a->margin);
    uint64_t texels = 0;
    for (size_t p = 0; p < a->page_count; p++) {
        assert_true(a->pages[p].width > 0 && a->pages[p].height > 0);
        assert_int_equal(a->pages[p].width % 4, 0);
        assert_int_equal(a->pages[p].height % 4, 0);
        assert_true(a->pages[p].width <= max_page && a->pages[p].height <= max_page);
        texels += (uint64_t)a->pages[p].width * (uint64_t)a->pages[p].height;
    }
    assert_int_equal(texels, a->texels);
    /* occupancy grids: object rectangles, and chart blocks (content + margin) */
    for (size_t p = 0; p < a->page_count; p++) {
        int w = a->pages[p].width, h = a->pages[p].height;
        uint8_t *objs = calloc((size_t)w * (size_t)h, 1), *blocks = calloc((size_t)w * (size_t)h, 1);
        assert_non_null(objs);
        assert_non_null(blocks);
        for (size_t o = 0; o < a->object_count; o++) {
            const bk_atlas_object *ob = &a->objects[o];
            if (ob->page != (int32_t)p) continue;
            assert_true(ob->x >= 0 && ob->y >= 0 && ob->x + ob->w <= w && ob->y + ob->h <= h);
            for (int y = ob->y; y < ob->y + ob->h; y++)
                for (int x = ob->x; x < ob->x + ob->w; x++) {
                    assert_int_equal(objs[(size_t)y * (size_t)w + (size_t)x], 0);
                    objs[(size_t)y * (size_t)w + (size_t)x] = 1;
                }
            for (uint32_t c = ob->first_chart; c < ob->first_chart + ob->chart_count; c++) {
                const bk_atlas_chart *ch = &a->charts[c];
                assert_int_equal(ch->page, ob->page);
                assert_int_equal(ch->slot, o);
                int bx = ch->x - a->margin, by = ch->y - a->margin, bw = ch->w + 2 * a->margin,
                    bh = ch->h + 2 * a->margin;
                /* the block lies inside the object rectangle */
                assert_true(bx >= ob->x && by >= ob->y && bx + bw <= ob->x + ob->w && by + bh <= ob->y + ob->h);
                for (int y = by; y < by + bh; y++)
                    for (int x = bx; x < bx + bw; x++) {
                        assert_int_equal(blocks[(size_t)y * (size_t)w + (size_t)x], 0);
                        blocks[(size_t)y * (size_t)w + (size_t)x] = 1;
                    }
                /* every corner of its triangles inside the content rectangle; generated charts
                 * are never mirrored (a turn is a rotation): their triangles stay counter-
                 * clockwise in page coordinates, whatever the packer did */
                assert_true(ch->quarter_turns <= 2);
                if (ob->uv_source != BK_UV_GENERATED) assert_int_equal(ch->quarter_turns, 0);
                for (uint32_t t = ch->first; t < ch->first + ch->count; t++) {
                    assert_int_equal(a->tri_chart[t], c);
                    assert_int_equal(a->scene_tri_entry[a->tris[t]], (int32_t)t);
                    const float *q = a->tri_uv + 6 * (size_t)t;
                    double orient = ((double)q[2] - q[0]) * ((double)q[5] - q[1]) - ((double)q[3] - q[1]) * ((double)q[4] - q[0]);
                    if (ob->uv_source == BK_UV_GENERATED) assert_true(orient > 0.0);
                    for (int k = 0; k < 3; k++) {
                        float u = a->tri_uv[6 * t + 2 * (size_t)k], v = a->tri_uv[6 * t + 2 * (size_t)k + 1];
                        assert_true(u >= (float)ch->x && u <= (float)(ch->x + ch->w));
                        assert_true(v >= (float)ch->y && v <= (float)(ch->y + ch->h));
                    }
                }
            }
        }
        free(objs);
        free(blocks);
    }
    /* pairwise: the content of two charts on a page is at least `padding` texels apart */
    for (size_t i = 0; i < a->chart_count; i++)
        for (size_t j = i + 1; j < a->chart_count; j++) {
            const bk_atlas_chart *p = &a->charts[i], *q = &a->charts[j];
            if (p->page != q->page) continue;
            int gx = q->x >= p->x + p->w ? q->x - (p->x + p->w) : p->x >= q->x + q->w ? p->x - (q->x + q->w) : -1;
            int gy = q->y >= p->y + p->h ? q->y - (p->y + p->h) : p->y >= q->y + q->h ? p->y - (q->y + q->h) : -1;
            assert_true(gx >= a->padding || gy >= a->padding);
        }
    /* lightmap vertices agree with the triangle corners */
    for (size_t o = 0; o < a->object_count; o++) {
        const bk_object *ob = &s->objects[a->objects[o].object];
        for (uint32_t i = 0; i < ob->tri_count; i++) {
            size_t tri = (size_t)ob->first_tri + i;
            int32_t e = a->scene_tri_entry[tri];
            for (int k = 0; k < 3; k++) {
                uint32_t v = a->scene_tri_vertices[3 * tri + (size_t)k];
                assert_true(v < a->vertex_count);
                assert_int_equal(a->vertex_slot[v], o);
                if (e < 0) continue;
                assert_int_equal(a->vertex_source[v], s->tris[3 * tri + (size_t)k]);
                const bk_atlas_page *pg = &a->pages[a->charts[a->tri_chart[e]].page];
                assert_float_equal(a->vertex_uv[2 * v] * (float)pg->width, a->tri_uv[6 * (size_t)e + 2 * (size_t)k], 1e-3);
                assert_float_equal(a->vertex_uv[2 * v + 1] * (float)pg->height,
                                   a->tri_uv[6 * (size_t)e + 2 * (size_t)k + 1], 1e-3);
            }
        }
    }
}

static void test_layout_rules(void **state)
{
    (void)state;
    bk_scene s;
    mixed_scene(&s);
    bk_atlas_options o = {0};
    o.default_density = 24.0f;
    o.page_size = 128; /* small pages: forces several */
    o.max_page_size = 128;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_int_equal(a.object_count, s.object_count);
    assert_true(a.page_count >= 2);
    /* full pages share one size: page_size, or more when one object needs it */
    int biggest = 0;
    for (size_t i = 0; i < a.object_count; i++) {
        if (a.objects[i].w > biggest) biggest = a.objects[i].w;
        if (a.objects[i].h > biggest) biggest = a.objects[i].h;
    }
    int full = biggest > 128 ? (biggest + 3) / 4 * 4 : 128;
    for (size_t p = 0; p + 1 < a.page_count; p++) {
        assert_int_equal(a.pages[p].width, full);
        assert_int_equal(a.pages[p].height, full);
    }
    assert_int_equal(a.tri_count, s.tri_count);
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);

    /* wider padding is honoured too */
    o.padding = 5;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_int_equal(a.padding, 6);
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);
    uvs_free(&s);
}

static void test_deterministic(void **state)
{
    (void)state;
    bk_scene s;
    mixed_scene(&s);
    bk_atlas_options o = {0};
    o.default_density = 20.0f;
    o.page_size = 256;
    bk_atlas a, b;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &b), LBK_OK);
    assert_int_equal(a.page_count, b.page_count);
    assert_int_equal(a.chart_count, b.chart_count);
    assert_int_equal(a.vertex_count, b.vertex_count);
    assert_memory_equal(a.pages, b.pages, a.page_count * sizeof *a.pages);
    assert_memory_equal(a.objects, b.objects, a.object_count * sizeof *a.objects);
    assert_memory_equal(a.charts, b.charts, a.chart_count * sizeof *a.charts);
    assert_memory_equal(a.tri_uv, b.tri_uv, a.tri_count * 6 * sizeof(float));
    assert_memory_equal(a.vertex_uv, b.vertex_uv, a.vertex_count * 2 * sizeof(float));
    assert_memory_equal(a.scene_tri_vertices, b.scene_tri_vertices, s.tri_count * 3 * sizeof(uint32_t));
    bk_atlas_free(&a);
    bk_atlas_free(&b);
    uvs_free(&s);
}

/* Texel density: a 1 m quad at d texels/m spans d texels (within 1), from the object's
 * lbk_texel_density, the default, or the override. */
static void test_density(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    const float dens[] = {5.0f, 8.0f, 16.0f, 0.0f, 13.0f};
    for (int i = 0; i < 5; i++) {
        uint32_t o = add_quad_object(&s, "q", 2.0f * (float)i, 0, 1.0f, 1.0f, 0, 2);
        s.objects[o].texel_density = dens[i];
    }
    bk_atlas_options opt = {0};
    opt.default_density = 11.0f;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &opt, &a), LBK_OK);
    for (int i = 0; i < 5; i++) {
        float want = dens[i] > 0 ? dens[i] : 11.0f;
        const bk_atlas_object *ob = &a.objects[i];
        assert_float_equal(ob->requested_density, want, 0);
        assert_float_equal(ob->density, want, 1e-4);
        assert_int_equal(ob->chart_count, 1);
        const bk_atlas_chart *ch = &a.charts[ob->first_chart];
        /* covered extent of the triangles: d texels, content rectangle ceil(d) */
        float mnx = 1e9f, mxx = -1e9f, mny = 1e9f, mxy = -1e9f;
        for (uint32_t t = ch->first; t < ch->first + ch->count; t++)
            for (int k = 0; k < 3; k++) {
                mnx = fminf(mnx, a.tri_uv[6 * t + 2 * (size_t)k]);
                mxx = fmaxf(mxx, a.tri_uv[6 * t + 2 * (size_t)k]);
                mny = fminf(mny, a.tri_uv[6 * t + 2 * (size_t)k + 1]);
                mxy = fmaxf(mxy, a.tri_uv[6 * t + 2 * (size_t)k + 1]);
            }
        assert_float_equal(mxx - mnx, want, 1.0);
        assert_float_equal(mxy - mny, want, 1.0);
        assert_true(abs(ch->w - (int)want) <= 1 && abs(ch->h - (int)want) <= 1);
        assert_int_equal(ob->w, ch->w + 2 * a.margin);
    }
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);

    /* the override wins over object values */
    opt.density_override = 6.0f;
    assert_int_equal(bk_atlas_build(&s, NULL, &opt, &a), LBK_OK);
    for (int i = 0; i < 5; i++) {
        assert_float_equal(a.objects[i].density, 6.0f, 1e-4);
        assert_int_equal(a.charts[a.objects[i].first_chart].w, 6);
    }
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Over budget: one uniform factor, reported, and the result within the budget. */
static void test_budget_scaling(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    add_quad_object(&s, "floor", 0, 0, 50, 50, 0, 8);
    add_quad_object(&s, "wall", 0, 0, 10, 10, 3, 2);
    bk_atlas_options o = {0};
    o.default_density = 16.0f;
    o.texel_budget = 200000; /* asks for 800² + 160² ≈ 666k */
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_true(a.density_scale < 1.0f && a.density_scale > 0.3f);
    assert_non_null(strstr(a.note, "budget"));
    uint64_t sum = 0;
    for (size_t i = 0; i < a.object_count; i++) sum += (uint64_t)a.objects[i].w * (uint64_t)a.objects[i].h;
    assert_true(sum <= o.texel_budget);
    /* both objects scaled by the same factor */
    assert_float_equal(a.objects[0].density, 16.0f * a.density_scale, 1e-3);
    assert_float_equal(a.objects[1].density, 16.0f * a.density_scale, 1e-3);
    /* and the factor is not needlessly small: the result fills at least 80% of the budget */
    assert_true((double)sum >= 0.8 * (double)o.texel_budget);
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);

    /* within budget: no scaling, no note */
    o.texel_budget = 0;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_float_equal(a.density_scale, 1.0f, 0);
    assert_string_equal(a.note, "");
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Only what is needed: one small quad gets one small page; no objects, no pages. */
static void test_small_scene_small_page(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    add_quad_object(&s, "tile", 0, 0, 1, 1, 0, 1);
    bk_atlas_options o = {0};
    o.default_density = 8.0f;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_int_equal(a.page_count, 1);
    /* 8 texels + 2·1 margin = 10 → 12 (multiple of 4) */
    assert_int_equal(a.pages[0].width, 12);
    assert_int_equal(a.pages[0].height, 12);
    assert_int_equal(a.texels, 144);
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);

    /* nothing selected */
    uint8_t none[1] = {0};
    assert_int_equal(bk_atlas_build(&s, none, &o, &a), LBK_OK);
    assert_int_equal(a.page_count, 0);
    assert_int_equal(a.object_count, 0);
    assert_int_equal(a.texels, 0);
    assert_int_equal(a.object_slot[0], -1);
    assert_int_equal(a.scene_tri_entry[0], -1);
    assert_int_equal(a.scene_tri_vertices[0], UINT32_MAX);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Several quads in one page: the page is repacked near-square rather than one long row. */
static void test_last_page_tight(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    for (int i = 0; i < 16; i++) add_quad_object(&s, "t", (float)i, 0, 1, 1, 0, 1);
    bk_atlas_options o = {0};
    o.default_density = 8.0f;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_int_equal(a.page_count, 1);
    /* 16 blocks of 10×10 = 1600 texels; a 4×4 arrangement fits 40×40 */
    assert_true(a.texels <= 44 * 44);
    assert_true(a.pages[0].width <= 2 * a.pages[0].height && a.pages[0].height <= 2 * a.pages[0].width);
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Selection mask, a too-large object (lower density, noted), degenerate-only object. */
static void test_selection_and_limits(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    add_quad_object(&s, "a", 0, 0, 1, 1, 0, 1);
    add_quad_object(&s, "b", 0, 0, 1, 1, 1, 1);
    add_quad_object(&s, "huge", 0, 0, 100, 100, 2, 4);
    uvs_object(&s, "dust");
    float c0[3] = {0, 0, 0}, c1[3] = {1, 1, 1}, c2[3] = {2, 2, 2};
    uvs_tri(&s, c0, c1, c2, 0);
    uint8_t sel[4] = {1, 0, 1, 1};
    bk_atlas_options o = {0};
    o.default_density = 10.0f;
    o.page_size = 256;
    o.max_page_size = 512;
    o.texel_budget = 1u << 30;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, sel, &o, &a), LBK_OK);
    assert_int_equal(a.object_count, 3);
    assert_int_equal(a.object_slot[0], 0);
    assert_int_equal(a.object_slot[1], -1);
    assert_int_equal(a.object_slot[2], 1);
    assert_int_equal(a.object_slot[3], 2);
    /* huge: 1000 texels asked, a 512 page fits at most 510 */
    const bk_atlas_object *h = &a.objects[1];
    assert_true(h->density < 10.0f);
    assert_true(h->w <= 512 && h->h <= 512);
    assert_non_null(strstr(h->note, "density lowered"));
    /* dust: nothing to lightmap, no page, but its corners have lightmap vertices */
    assert_int_equal(a.objects[2].page, -1);
    assert_int_equal(a.objects[2].chart_count, 0);
    assert_int_equal(a.objects[2].degenerate_tris, 1);
    /* the unselected object has no entries */
    for (uint32_t t = s.objects[1].first_tri; t < s.objects[1].first_tri + s.objects[1].tri_count; t++) {
        assert_int_equal(a.scene_tri_entry[t], -1);
        assert_int_equal(a.scene_tri_vertices[3 * t], UINT32_MAX);
    }
    check_layout(&s, &a, 512);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* A huge triangle and ten 10 m quads at 4 texels/m over a 300 000 texel budget: the triangle
 * (2000 texels a leg) alone would take a 1024 page, so its chart shrinks until the level fits,
 * and every quad keeps 4 texels/m — its 40-texel chart in a 42-texel rectangle — with no
 * level-wide scaling. */
static void test_budget_shrinks_huge_triangles_first(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "ground");
    float t0[3] = {0, -1, 0}, t1[3] = {500, -1, 0}, t2[3] = {0, -1, -500};
    uvs_tri(&s, t0, t1, t2, 0);
    for (int i = 0; i < 10; i++) {
        char name[16];
        snprintf(name, sizeof name, "q%d", i);
        add_quad_object(&s, name, 12.0f * (float)i, 0, 10, 10, 0, 1);
    }
    uvs_update_bounds(&s);
    bk_atlas_options o = {0};
    o.default_density = 4.0f;
    o.page_size = 256;
    o.max_page_size = 1024;
    o.texel_budget = 300000;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    assert_float_equal(a.density_scale, 1.0, 0.0);
    assert_string_equal(a.note, "");
    uint64_t rects = 0;
    for (size_t i = 0; i < a.object_count; i++) {
        const bk_atlas_object *ob = &a.objects[i];
        rects += (uint64_t)ob->w * (uint64_t)ob->h;
        assert_float_equal(ob->density, 4.0, 1e-6);
        if (i == 0) {
            assert_non_null(strstr(ob->note, "1 triangle longer than"));
            assert_true(ob->w < 1024 && ob->h < 1024);
        } else {
            assert_int_equal(ob->w, 42);
            assert_int_equal(ob->h, 42);
        }
    }
    assert_true(rects <= 300000);
    check_layout(&s, &a, 1024);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Lightmap vertices: a cube with one shared vertex set per face keeps 4 per face; a sphere
 * (all vertices shared) duplicates exactly the seam vertices. */
static void test_vertex_split(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "cube");
    float mn[3] = {0, 0, 0}, mx[3] = {1, 1, 1};
    uvs_box(&s, mn, mx, 1, 0, 0);
    uvs_object(&s, "sphere");
    float c[3] = {3, 0, 0};
    uvs_sphere(&s, c, 1.0f, 16, 8, 0);
    bk_atlas a;
    bk_atlas_options o = {0};
    o.default_density = 10.0f;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    size_t cube_v = 0, sphere_v = 0;
    for (size_t v = 0; v < a.vertex_count; v++) {
        if (a.vertex_slot[v] == 0) cube_v++;
        else sphere_v++;
    }
    assert_int_equal(cube_v, 24);
    size_t sphere_src = 16 * 7 + 2;
    assert_true(sphere_v > sphere_src);         /* seams exist */
    assert_true(sphere_v < 2 * sphere_src);     /* but only seams are split */
    check_layout(&s, &a, 4096);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* Long thin strips make the packer turn charts (and objects). A turn is a rotation of the
 * chart: every triangle keeps its world edge lengths × density in texels, stays counter-
 * clockwise, and the tangent frame rule holds on turned charts too (the texel to the right lies
 * one texel along T, the one below one texel along B = N × T). */
static void test_turns_keep_mapping(void **state)
{
    (void)state;
    bk_scene s;
    uvs_init(&s);
    uvs_object(&s, "strips");
    for (int i = 0; i < 12; i++) {
        float len = 0.5f + 0.13f * (float)i, z = -0.3f * (float)i;
        float p0[3] = {0, 0, z}, p1[3] = {len, 0, z}, p2[3] = {len, 0, z - 0.1f}, p3[3] = {0, 0, z - 0.1f};
        uvs_quad(&s, p0, p1, p2, p3, 1, 0, NULL, 1.0f);
    }
    for (int i = 0; i < 10; i++) {
        char name[32];
        snprintf(name, sizeof name, "plank%d", i);
        add_quad_object(&s, name, 5.0f + (float)i, 0, 0.15f, 0.6f + 0.2f * (float)i, 0, 1);
    }
    bk_atlas_options o = {0};
    o.default_density = 20.0f;
    bk_atlas a;
    assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
    check_layout(&s, &a, 4096);
    size_t turned = 0;
    for (size_t c = 0; c < a.chart_count; c++) turned += a.charts[c].quarter_turns & 1;
    assert_true(turned >= 3);
    assert_true(turned < a.chart_count);
    for (size_t t = 0; t < a.tri_count; t++) {
        const float *q = a.tri_uv + 6 * t;
        for (int k = 0; k < 3; k++) {
            const float *pa = s.positions + 3 * s.tris[3 * a.tris[t] + (size_t)k];
            const float *pb = s.positions + 3 * s.tris[3 * a.tris[t] + (size_t)((k + 1) % 3)];
            double wl = sqrt(((double)pb[0] - pa[0]) * ((double)pb[0] - pa[0]) + ((double)pb[2] - pa[2]) * ((double)pb[2] - pa[2]));
            double du = (double)q[2 * ((k + 1) % 3)] - q[2 * k], dv = (double)q[2 * ((k + 1) % 3) + 1] - q[2 * k + 1];
            assert_float_equal(sqrt(du * du + dv * dv), 20.0 * wl, 1e-3 * 20.0 * wl + 1e-4);
        }
    }
    bk_texels tx;
    assert_int_equal(bk_texels_build(&s, &a, &tx), LBK_OK);
    size_t checked = 0, checked_turned = 0;
    for (size_t i = 0; i < tx.count; i++) {
        const bk_texel *r = &tx.receivers[i], *right = bk_texels_at(&tx, r->page, r->x + 1, r->y),
                      *down = bk_texels_at(&tx, r->page, r->x, r->y + 1);
        if (!right || !down || (r->flags | right->flags | down->flags) & BK_TEXEL_EDGE) continue;
        uint32_t c = a.tri_chart[a.scene_tri_entry[r->tri]];
        if (c != a.tri_chart[a.scene_tri_entry[right->tri]] || c != a.tri_chart[a.scene_tri_entry[down->tri]]) continue;
        float b[3] = {r->normal[1] * r->tangent[2] - r->normal[2] * r->tangent[1],
                      r->normal[2] * r->tangent[0] - r->normal[0] * r->tangent[2],
                      r->normal[0] * r->tangent[1] - r->normal[1] * r->tangent[0]};
        for (int k = 0; k < 3; k++) {
            assert_float_equal(right->position[k] - r->position[k], r->tangent[k] * r->texel_size, 1e-4);
            assert_float_equal(down->position[k] - r->position[k], b[k] * r->texel_size, 1e-4);
        }
        checked++;
        checked_turned += a.charts[c].quarter_turns & 1;
    }
    assert_true(checked > 200);
    assert_true(checked_turned > 20);
    bk_texels_free(&tx);
    bk_atlas_free(&a);
    uvs_free(&s);
}

/* A deterministic pseudo-random size in [lo, hi). */
static float lcg_size(uint32_t *st, float lo, float hi)
{
    *st = *st * 1664525u + 1013904223u;
    return lo + (hi - lo) * (float)(*st >> 8) / 16777216.0f;
}

/* Fill on many charts at the default padding 2: 150 quads of 0.3–2.5 m (16 texels/m) as
 * objects of their own, and the same quads as 150 charts of one object. Covered texels / page
 * texels must reach the 80 % goal (the block rings alone cost ~10 % at these sizes). */
static void test_fill_many_charts(void **state)
{
    (void)state;
    for (int one_object = 0; one_object < 2; one_object++) {
        bk_scene s;
        uvs_init(&s);
        uint32_t st = 12345u;
        if (one_object) uvs_object(&s, "all");
        for (int i = 0; i < 150; i++) {
            float w = lcg_size(&st, 0.3f, 2.5f), d = lcg_size(&st, 0.3f, 2.5f);
            if (!one_object) {
                char name[32];
                snprintf(name, sizeof name, "q%d", i);
                uvs_object(&s, name);
            }
            float x = 3.0f * (float)i, p0[3] = {x, 0, 0}, p1[3] = {x + w, 0, 0}, p2[3] = {x + w, 0, -d}, p3[3] = {x, 0, -d};
            uvs_quad(&s, p0, p1, p2, p3, 1, 0, NULL, 1.0f);
        }
        bk_atlas_options o = {0};
        o.default_density = 16.0f;
        bk_atlas a;
        assert_int_equal(bk_atlas_build(&s, NULL, &o, &a), LBK_OK);
        check_layout(&s, &a, 4096);
        bk_atlas_stats stt;
        assert_int_equal(bk_atlas_stats_compute(&a, &stt), LBK_OK);
        assert_int_equal(stt.charts, 150);
        assert_true(stt.fill >= 0.80);
        assert_true(stt.fill_rects >= stt.fill);
        bk_atlas_free(&a);
        uvs_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_budget_shrinks_huge_triangles_first),
        cmocka_unit_test(test_layout_rules),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_density),
        cmocka_unit_test(test_budget_scaling),
        cmocka_unit_test(test_small_scene_small_page),
        cmocka_unit_test(test_last_page_tight),
        cmocka_unit_test(test_selection_and_limits),
        cmocka_unit_test(test_vertex_split),
        cmocka_unit_test(test_turns_keep_mapping),
        cmocka_unit_test(test_fill_many_charts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
