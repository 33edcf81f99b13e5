/* The scene against OBJS (objects_match.h). */
#include "tools/common/objects_match.h"

#include <stdlib.h>
#include <string.h>

#include "tools/common/error_util.h"

int tl_objects_match(const bk_scene *s, const lbk_objects_view *objs, int status, int internal, char err[TL_ERR_LEN])
{
    if (!objs || objs->count != s->object_count)
        return tl_fail(err, status, "the scene has %zu objects, the container %u: not the scene it was baked from",
                       s->object_count, objs ? objs->count : 0);
    size_t cap = 0;
    float *xyz = NULL;
    int rc = 0;
    for (size_t i = 0; i < s->object_count && !rc; i++) {
        const bk_object *o = &s->objects[i];
        if (o->tri_count > cap) { /* one buffer, as large as the largest object */
            free(xyz);
            cap = o->tri_count;
            if (!(xyz = malloc(cap * 9 * sizeof *xyz))) return tl_fail(err, internal, "out of memory");
        }
        for (size_t k = 0; k < 3 * (size_t)o->tri_count; k++)
            memcpy(&xyz[3 * k], &s->positions[3 * (size_t)s->tris[3 * (size_t)o->first_tri + k]], 3 * sizeof(float));
        const lbk_result r = lbk_objects_geometry_check(objs, (uint32_t)i, xyz, o->tri_count);
        if (r == LBK_ERR_MISMATCH)
            rc = tl_fail(err, status,
                         "object %zu ('%.60s'): its geometry differs from the container's (geometry hash): not the scene "
                         "it was baked from",
                         i, o->name);
        else if (r != LBK_OK)
            rc = tl_fail(err, status, "object %zu ('%.60s'): %s", i, o->name, lbk_result_message(r));
    }
    free(xyz);
    return rc;
}
