/* The probes a ray-length-limited final gather falls back on (gather_limit.h). */
#include "bake/pipeline/gather_limit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake/encode/encode.h"
#include "lbk/sh.h"

lbk_result bk_far_probes_bake(const bk_pipeline *b, const bk_transport_options *base, bk_far_probes *out)
{
    memset(out, 0, sizeof *out);
    const size_t n = b->llg_first - b->glg_first;
    if (!b->have_glg || n < 4) return LBK_OK;
    bk_transport_options to = *base;
    memset(to.class_end, 0, sizeof to.class_end); /* probes only: one class */
    to.octa_points = NULL, to.octa_count = 0;
    to.gather_limit = 0, to.far_radiance = NULL;
    to.report = NULL; /* the bake's pass log and report are the base run's */
    /* a cache of the default budget instead of one as fine as the lightmap: the probes are read
     * as a smooth field, and a texel-fine cache is most of a run's cost */
    to.cell_size = NULL;
    lbk_sh9_rgb *sh = calloc(n, sizeof *sh);
    uint8_t(*vis)[4] = calloc(b->glg.tet_count ? b->glg.tet_count : 1, sizeof *vis);
    lbk_result r = sh && vis ? LBK_OK : LBK_ERR_OUT_OF_MEMORY;
    if (!r) {
        bk_transport_output o;
        memset(&o, 0, sizeof o);
        o.radiance = sh;
        bk_transport_stats st;
        r = bk_transport_run(&b->scene, b->tracer, &b->receivers[b->glg_first], n, &to, &o, &st);
    }
    if (!r) {
        bk_glg_visibility_unorm8(&b->glg, vis);
        lbk_glg_build_desc d;
        memset(&d, 0, sizeof d);
        d.probe_count = (uint32_t)n;
        d.tetra_count = (uint32_t)b->glg.tet_count;
        d.positions = (const float(*)[3])b->glg.positions; /* the scene's frame: the transport's */
        d.probes = sh;
        d.tetras = (const uint32_t(*)[4])b->glg.tets;
        d.adjacency = (const uint32_t(*)[4])b->glg.neighbours;
        d.visibility = (const uint8_t(*)[4])vis;
        d.scale = bk_scale_for(bk_probe_max(sh, n));
        size_t size;
        r = lbk_glg_build(&d, NULL, &out->bytes, &size);
        if (!r) r = lbk_glg_open(out->bytes, size, &out->view);
    }
    free(sh), free(vis);
    if (r) bk_far_probes_free(out);
    return r;
}

int bk_far_probes_radiance(void *user, const double x[3], const double d[3], uint32_t *hint, double L[3])
{
    const bk_far_probes *f = user;
    const float p[3] = {(float)x[0], (float)x[1], (float)x[2]}, df[3] = {(float)d[0], (float)d[1], (float)d[2]};
    lbk_sh9_rgb sh;
    lbk_glg_sample_info info;
    float rgb[3] = {0, 0, 0};
    if (lbk_glg_sample(&f->view, p, hint, &sh, &info) != LBK_OK || !info.location.inside) return 0;
    lbk_sh9_eval(&sh, df, rgb);
    for (int a = 0; a < 3; a++) L[a] = rgb[a] > 0 && isfinite(rgb[a]) ? rgb[a] : 0;
    return 1;
}

void bk_far_probes_free(bk_far_probes *f)
{
    lbk_free(NULL, f->bytes);
    memset(f, 0, sizeof *f);
}
