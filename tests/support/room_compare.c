#include "room_compare.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "lbk/ahd.h"
#include "tools/common/set_decode.h"

rc_result rc_compare_room(rc_side a, rc_side b)
{
    for (int k = 3; k < 5; k++) assert_int_equal(a.rect[k], b.rect[k]);
    lbk_lmap_page pa, pb;
    assert_int_equal(lbk_lmap_page_get(a.lmap, a.rect[0], &pa), LBK_OK);
    assert_int_equal(lbk_lmap_page_get(b.lmap, b.rect[0], &pb), LBK_OK);
    double diff = 0, sa = 0, sb = 0;
    for (uint32_t y = 0; y < a.rect[4]; y++)
        for (uint32_t x = 0; x < a.rect[3]; x++) {
            uint64_t ia = pa.first_texel + (uint64_t)(a.rect[2] + y) * pa.width + a.rect[1] + x;
            uint64_t ib = pb.first_texel + (uint64_t)(b.rect[2] + y) * pb.width + b.rect[1] + x;
            /* physical: stored × each file's LMAP scale (spec §5.7) */
            double va = tl_texel_lum(a.z[ia], &a.rgba[4 * ia]) * pa.scale;
            double vb = tl_texel_lum(b.z[ib], &b.rgba[4 * ib]) * pb.scale;
            diff += fabs(va - vb), sa += va, sb += vb;
        }
    rc_result r = {sb > 0 ? diff / sb : 0, sb > 0 ? sa / sb : 0, sa, sb};
    return r;
}
