/* Section type → describer. */
#include <math.h>

#include "tools/inspect/describe.h"
#include "lbk/error_map.h"
#include "lbk/lbk.h"

inspect_describe_fn inspect_describer(uint32_t type)
{
    switch (type) {
    case LBK_SECTION_META: return inspect_describe_meta;
    case LBK_SECTION_REPT: return inspect_describe_rept;
    case LBK_SECTION_OBJS: return inspect_describe_objs;
    case LBK_SECTION_LMAP: return inspect_describe_lmap;
    case LBK_SECTION_GLG: return inspect_describe_glg;
    case LBK_SECTION_LLG: return inspect_describe_llg;
    case LBK_SECTION_OCTP: return inspect_describe_octp;
    case LBK_SECTION_DLS: return inspect_describe_dls;
    case LBK_SECTION_DOOR: return inspect_describe_door;
    case LBK_SECTION_LMUV: return inspect_describe_lmuv;
    case LBK_SECTION_TERR: return inspect_describe_terr;
    default: return NULL;
    }
}

int inspect_scale_log2(float scale)
{
    int e;
    frexpf(scale, &e); /* scale = 1/2 · 2^e exactly */
    return e - 1;
}
