/* Whether a container's OBJS describes the scene a reader loaded: the same number of objects, and
 * each object's geometry the one that was baked (liblbk's lbk_objects_geometry_check over the
 * imported triangles). The check lbk render and lbk export --gltf (so lbk view) make before they
 * use any lighting, so that they accept and refuse the same pairs of files. */
#ifndef LBK_TOOLS_OBJECTS_MATCH_H
#define LBK_TOOLS_OBJECTS_MATCH_H

#include "lbk/objects.h"
#include "scene/scene.h"
#include "tools/common/image_io.h" /* TL_ERR_LEN */

/* objs: NULL when the container has no OBJS. Returns 0, or `status` (`internal` when out of
 * memory) with the reason in err. */
int tl_objects_match(const bk_scene *s, const lbk_objects_view *objs, int status, int internal, char err[TL_ERR_LEN]);

#endif
