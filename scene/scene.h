/* The baker's scene: what glTF import produces and every later phase consumes.
 * Plain C, world space, metres, linear colour. Units: emission is radiance (emissiveFactor ×
 * emissiveTexture × KHR_materials_emissive_strength, taken as cd/m²); point and spot
 * intensity is in candela, directional in lux, as KHR_lights_punctual defines them; hence
 * irradiance results are in lux-like units (lm/m²) and radiance in nits. */
#ifndef BK_SCENE_H
#define BK_SCENE_H

#include <stddef.h>
#include <stdint.h>

/* The highest texel density (texels per metre) anything accepts: lbk/bake.h's
 * LBK_BAKE_TEXEL_DENSITY_MAX, which bake/pipeline asserts equal (this library sits below it). */
#define BK_TEXEL_DENSITY_MAX 10000.0

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bk_image {          /* linear RGBA float, row 0 at the top (v = 0) */
    int width, height;
    float *rgba;
    float mean[4];                 /* average over all texels (import fills it; the albedo
                                      average is what most of the baker needs) */
} bk_image;

typedef struct bk_material {
    char name[64];
    float albedo[3];               /* baseColorFactor (linear); multiplied by albedo_tex if any */
    float emission[3];             /* radiance; multiplied by emission_tex if any */
    int albedo_tex;                /* index into scene images, -1 none (sampled with uv0) */
    int emission_tex;              /* index into scene images, -1 none (sampled with uv0) */
    int double_sided;
    /* glTF metallic-roughness (bake/transport/GGX.md); zero is a Lambertian material, as before */
    float metallic;                /* metallicFactor in [0, 1] (import: the glTF default 1) */
    float roughness;               /* roughnessFactor in [0, 1] (import: the glTF default 1) */
    int metal_rough_tex1;          /* 1 + index into scene images of the metallicRoughnessTexture
                                      (B = metallic, G = roughness, multiplied by the factors;
                                      sampled with uv0); 0 none, so a zeroed material has none */
    /* The glTF normalTexture, read only when bk_import_options.normal_maps asks (the renderer and
     * the viewer's export; the bake lights the interpolated normal, which is what AHD's direction
     * is stored against). Tangent-space, linear RGB (not sRGB-decoded), sampled with uv0 in the
     * frame of bk_scene.tangents: n = normalize(T·x + B·y + N·z), (x, y) = (2·rgb.xy − 1)·scale,
     * z = 2·rgb.z − 1, B = w·(N × T) (glTF 2.0 §3.9.3). */
    int normal_tex1;               /* 1 + index into scene images; 0 none */
    float normal_scale;            /* normalTexture.scale (finite; glTF default 1) */
} bk_material;

/* A material the transport treats as glossy (coupled diffuse + GGX, GGX.md): metallic > 0 or a
 * metallicRoughness texture. Every other material takes the Lambertian path of albedo
 * baseColor (the dielectric's 4 % specular ignored), so Lambertian scenes bake as before. */
static inline int bk_material_glossy(const bk_material *m)
{
    return m->metallic > 0 || m->metal_rough_tex1 > 0;
}

enum bk_lighting { BK_LIGHTING_AUTO = 0, BK_LIGHTING_LIGHTMAP, BK_LIGHTING_LLG, BK_LIGHTING_NONE };

typedef struct bk_object {         /* one glTF node that instantiates a mesh */
    char name[128];                /* node name, or "node<i>" */
    uint64_t geometry_hash;        /* XXH3-64 of the object's local-space positions and indices */
    uint32_t first_tri, tri_count; /* range in bk_scene.tris */
    int lighting;                  /* enum bk_lighting, from extras lbk_lighting */
    float texel_density;           /* texels per metre from extras lbk_texel_density, in
                                      (0, BK_TEXEL_DENSITY_MAX]; 0: default */
    char light_set[64];            /* extras lbk_light_set ("" none): emissive triangles join that set */
    char door[64];                 /* extras lbk_door ("" none): the object is a door, closed state */
    int has_uv1;                   /* TEXCOORD_1 present on all its primitives */
    float local_to_world[16];      /* column-major, as glTF */
    /* provenance (import fills it; meaningful only when bk_scene.primitives is set) */
    int32_t node;                  /* the glTF node */
    int mirrored;                  /* negative determinant: import swapped corners 1 and 2 of every
                                      triangle to keep counter-clockwise front faces in world space */
} bk_object;

/* One glTF triangle primitive as an object instanced it (provenance for lightmap UVs, spec
 * container.md §16: an engine rebuilds the primitive from the glTF). Its triangles are the
 * primitive's in order (strip/fan restarts dropped), its vertices the primitive's in order
 * (split per triangle corner when the primitive has no NORMAL: flat shading). */
typedef struct bk_primitive {
    uint32_t object;               /* scene object */
    uint32_t gltf_primitive;       /* index in the glTF mesh's primitives array */
    uint32_t source_vertex_count;  /* vertices of the glTF primitive (POSITION count, or Draco points) */
    uint32_t first_tri, tri_count; /* range in bk_scene.tris, tri_count >= 1 */
    uint32_t first_vertex, vertex_count; /* range of bk_scene vertices */
} bk_primitive;

enum bk_light_type { BK_LIGHT_POINT = 0, BK_LIGHT_SPOT, BK_LIGHT_DIRECTIONAL };

typedef struct bk_light {
    char name[64];
    int type;                      /* enum bk_light_type */
    float color[3];                /* linear; intensity already multiplied in */
    float position[3];             /* world; point/spot */
    float direction[3];            /* world, unit, the direction light travels; spot/directional */
    float range;                   /* 0: infinite */
    float inner_cone, outer_cone;  /* radians; spot */
    char light_set[64];            /* "" : static light, baked into the base */
} bk_light;

/* A combination state (scene extras lbk_combinations, spec/authoring.md; seed 001 §6.2): two
 * doors, or a door and a light set, whose joint effect gets its own DLS set. */
typedef struct bk_combination {
    char members[2][64];           /* lbk_door or lbk_light_set names, as authored */
} bk_combination;

/* A box of playable space (node extras lbk_playable, spec/authoring.md): axis-aligned, in the
 * scene's frame (relative to bk_scene.origin), min < max on every axis. The GLG is denser inside
 * and coarser outside (bake/probes/PROBES.md). */
typedef struct bk_box {
    float min[3], max[3];
} bk_box;
#define BK_MAX_PLAYABLE 4096       /* import refuses more lbk_playable nodes than this */

/* A file the scene was read from (provenance: META input.files, spec/container.md §6.2). */
typedef struct bk_input_file {
    char path[256];                /* relative to the scene file's folder; the scene file by name */
    char role[8];                  /* "scene", "buffer", "image", "sky" */
    uint64_t bytes;
    uint64_t hash;                 /* XXH3-64 of the file's bytes */
} bk_input_file;

typedef struct bk_scene {
    /* vertices, world space */
    size_t vertex_count;
    float *positions;              /* 3 per vertex */
    float *normals;                /* 3 per vertex, unit (generated flat when the mesh has none) */
    float *uv0;                    /* 2 per vertex (0,0 when absent) */
    float *uv1;                    /* 2 per vertex; meaningful only where the object has_uv1 */
    /* 4 per vertex or NULL (only an import with normal_maps fills it): world-space unit tangent
     * T along +u of uv0, orthogonal to the normal, and w = ±1 with bitangent B = w·(N × T) along
     * −v (the normal map's +Y: up in the image). From the glTF's TANGENT where a primitive has it (and NORMAL), else derived from uv0 by
     * bk_scene_derive_tangents. */
    float *tangents;
    /* triangles */
    size_t tri_count;
    uint32_t *tris;                /* 3 vertex indices per triangle */
    uint32_t *tri_material;        /* per triangle */
    uint32_t *tri_object;          /* per triangle */
    /* provenance (NULL / 0 for scenes not made by import): vertex_source[v] is vertex v's index
     * in its glTF primitive; primitives in scene order, objects' triangles ascending */
    uint32_t *vertex_source;
    size_t primitive_count; bk_primitive *primitives;
    /* tables */
    size_t material_count;  bk_material *materials;
    size_t object_count;    bk_object *objects;
    size_t light_count;     bk_light *lights;
    size_t image_count;     bk_image *images;
    /* sky: uniform radiance, or an equirectangular image when sky_image >= 0 (then sky holds the
     * image's mean radiance, for information: it is not a multiplier). The image maps direction
     * d (y up) to u = 0.5 + atan2(d.x, -d.z)/(2π), v = acos(d.y)/π (row 0 = straight up). */
    float sky[3];
    int sky_image;
    /* provenance */
    uint64_t source_hash;          /* XXH3-64 of the source file bytes (and its buffers) */
    size_t input_count;            /* every file import read, in the order read (0 for scenes */
    bk_input_file *inputs;         /* not made by import) */
    float bounds_min[3], bounds_max[3];
    /* positions (vertices, lights, bounds) are relative to this point: world = position + origin.
     * The importer sets it for a level far from 0 (an integer number of metres per axis) before
     * positions become floats; 0 for scenes made otherwise. bk_object.local_to_world maps to the
     * world itself (its translation includes the origin). */
    double origin[3];
    /* combination states to bake (scene extras lbk_combinations); names are checked by the set
     * bakes (bake/sets/bake_sets.c), not by import */
    size_t combination_count;
    bk_combination *combinations;
    /* playable space (node extras lbk_playable); none: the GLG is placed as before */
    size_t playable_count;
    bk_box *playable;
} bk_scene;

/* Frees every array and image (all malloc'ed) and leaves an empty scene (all zero, sky_image
 * -1). NULL is fine. */
void bk_scene_free(bk_scene *scene);
/* bounds_min/bounds_max over all vertices (and point/spot light positions); an empty scene gets
 * min = max = 0. */
void bk_scene_compute_bounds(bk_scene *scene);
/* XXH3-64 over the raw bytes of `positions` (3 floats per vertex) followed by `indices`. */
uint64_t bk_geometry_hash(const float *positions, size_t vertex_count, const uint32_t *indices,
                          size_t index_count);
/* Fills every tangent whose w is 0 (bk_scene.tangents, which must be set) from the triangles
 * using it: per triangle the direction of +u of uv0 (and +v, for the sign), weighted by the
 * corner's angle and summed per vertex, then made orthogonal to the vertex normal
 * (Gram-Schmidt); w = +1 when the summed −v (the image's up, the normal map's +Y: uv (0, 0) is
 * the image's top left) lies on the side of N × T, else -1. This is the core
 * of MikkTSpace without its vertex splitting: vertices shared by triangles whose uv0 is mirrored
 * get one averaged frame. A vertex with no usable triangle (uv0 spans no area) gets any unit
 * tangent orthogonal to N, w = +1. Indices must be in range (bk_scene_check). Returns 0, or -1
 * when its scratch (48 bytes per vertex) cannot be allocated (nothing changed then). */
int bk_scene_derive_tangents(bk_scene *scene);
/* 1 when something emits: a punctual light with non-zero colour, a material with non-zero emission
 * used by at least one triangle, or a sky that is non-zero (uniform) or an image. The baker
 * refuses a scene without light unless the CLI supplies --sky. */
int bk_scene_has_light(const bk_scene *scene);
/* Structural check of a scene made by hand or by import: indices in range, finite data, unit
 * normals (±1e-3), image sizes. Returns 0 when valid, else writes the first problem to err. */
int bk_scene_check(const bk_scene *scene, char *err, size_t err_len);

#ifdef __cplusplus
}
#endif
#endif
