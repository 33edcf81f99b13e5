/* The normal-mapped floor of tests/tools/test_normal_maps.c and test_view_normal.c: a 4 × 4 m
 * floor (y = 0, facing +y, albedo NS_RHO, lightmapped) under one directional light of NS_E_SUN
 * lux from ns_light_dir, a black sky, and normal.png, a normal map of four stripes along u
 * (stripe k covers u in [k/4, (k+1)/4), x in [−2 + k, −1 + k]): flat, tilted by NS_ALPHA_DEG
 * towards +X, towards −X, towards +Y (the image's up, −v). uv0: u = (x + 2)/4, v = (z + 2)/4, so
 * the tangent frame is T = +x, B = −z, w = +1. Files are written into a folder the test owns. */
#ifndef LBK_TESTS_NORMAL_SCENE_H
#define LBK_TESTS_NORMAL_SCENE_H

#include <stdint.h>

#define NS_RHO 0.5
#define NS_E_SUN 3.0
#define NS_ALPHA_DEG 30.0
#define NS_NORMAL_TEX ",\"normalTexture\":{\"index\":0}"

/* stripe k's tangent-space normal as designed, and as the PNG's bytes decode (unit) in world space */
void ns_stripe_normal(int k, double n[3]);
void ns_world_normal(int k, double n[3]);
uint8_t ns_to_byte(double x);
/* towards the light: 40° from the zenith, from −z and +x */
void ns_light_dir(double l[3]);
/* The closed form of the stripe's radiance (nits): ρ/π · Ez · (1 + 2 n·l)/(1 + 2 N·l), Ez = E☉ N·l,
 * n the stripe's world normal (normal_mapped) or N; *lambert gets ρ/π · E☉ · max(0, n·l). */
double ns_closed_form(int k, int normal_mapped, double *lambert);

/* dir/normal.png, dir/floor.bin (TANGENT (1, 0, 0, tangent_w)) */
int ns_write_png(const char *dir);
int ns_write_floor_bin(const char *dir, float tangent_w);
/* dir/name over floor.bin and normal.png: tangent lists TANGENT; material_extra and node_extra
 * are JSON spliced into the material and the floor's node. */
int ns_write_gltf(const char *dir, const char *name, int tangent, const char *material_extra, const char *node_extra);
/* the same with the floor's lbk_lighting ("lightmap", "llg", "none"); other than "lightmap", a
 * static lightmapped copy of the floor stood up at x = 6 ("wall") makes the level the probes fill */
int ns_write_gltf_lit(const char *dir, const char *name, int tangent, const char *material_extra, const char *node_extra,
                      const char *lighting);
/* normal.png, floor.bin, derived.gltf (no TANGENT), authored.gltf (TANGENT), flat.gltf (no map) */
int ns_write_all(const char *dir, float tangent_w);

#endif
