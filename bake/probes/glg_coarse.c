/* The coarse probe pass of the GLG density rule: few samples, a small radiosity cache, a seed
 * of its own. Only the relative shape of the lighting matters to the rule, so noise well under
 * its threshold is enough (PROBES.md gives the numbers). */
#include "bake/probes/glg_coarse.h"

#include "bake/transport/transport.h"

#include <stdlib.h>
#include <string.h>

lbk_result bk_glg_coarse_lighting(void *user, const float *points, size_t n, float *out)
{
    bk_glg_coarse *g = user;
    if (!g || !g->scene || !g->tracer || (n && (!points || !out))) return LBK_ERR_INVALID_ARGUMENT;
    if (n == 0) return LBK_OK;
    bk_receiver *r = calloc(n, sizeof *r);
    lbk_sh9_rgb *sh = calloc(n, sizeof *sh);
    float *var = calloc(n, sizeof *var);
    if (!r || !sh || !var) { free(r); free(sh); free(var); return LBK_ERR_OUT_OF_MEMORY; }
    for (size_t i = 0; i < n; i++) memcpy(r[i].position, points + 3 * i, sizeof r[i].position);
    bk_transport_options to;
    memset(&to, 0, sizeof to);
    to.seed = g->seed ^ 0x676c67636f617273ull;   /* "glgcoars": not the bake's own streams */
    to.threads = g->threads;
    to.max_samples = g->samples > 0 ? g->samples : 256;
    to.target_error = -1;                        /* a fixed schedule: same work on every level */
    to.first_pass_samples = (to.max_samples + 1) / 2; /* one pass (two halves): one cache build */
    to.max_cells = g->max_cells > 0 ? g->max_cells : 4096;
    to.max_bounces = g->max_bounces > 0 ? g->max_bounces : 4;
    bk_transport_output o;
    memset(&o, 0, sizeof o);
    o.radiance = sh;
    o.variance = var;
    bk_transport_stats st;
    memset(&st, 0, sizeof st);
    lbk_result res = bk_transport_run(g->scene, g->tracer, r, n, &to, &o, &st);
    if (res == LBK_OK) {
        static const float dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (size_t i = 0; i < n; i++)
            for (int d = 0; d < 6; d++) {
                float e[3];
                lbk_sh9_irradiance(&sh[i], dirs[d], e);
                out[7 * i + d] = 0.2126f * e[0] + 0.7152f * e[1] + 0.0722f * e[2];
            }
        /* the transport's noise estimate of fluence/4 (TRANSPORT.md §Error estimate), one degree
         * of freedom: the same scale as a directional irradiance for light from all around */
        for (size_t i = 0; i < n; i++) out[7 * i + 6] = var[i];
        g->rays += st.rays;
        g->seconds += st.seconds;
    }
    free(r); free(sh); free(var);
    return res;
}
