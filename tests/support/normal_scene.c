/* The normal-mapped floor (see normal_scene.h). */
#include "support/normal_scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "tools/common/image_io.h"

#define PI 3.14159265358979323846

void ns_stripe_normal(int k, double n[3])
{
    const double a = NS_ALPHA_DEG * PI / 180.0, s = sin(a), c = cos(a);
    const double t[4][3] = {{0, 0, 1}, {s, 0, c}, {-s, 0, c}, {0, s, c}};
    memcpy(n, t[k & 3], sizeof t[0]);
}

uint8_t ns_to_byte(double x) { return (uint8_t)lround((x * 0.5 + 0.5) * 255.0); }

void ns_world_normal(int k, double n[3])
{
    double t[3];
    ns_stripe_normal(k, t);
    for (int c = 0; c < 3; c++) t[c] = 2.0 * ns_to_byte(t[c]) / 255.0 - 1.0;
    const double l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    n[0] = t[0] / l, n[1] = t[2] / l, n[2] = -t[1] / l; /* T = +x, B = −z, N = +y */
}

void ns_light_dir(double l[3])
{
    const double th = 40.0 * PI / 180.0, ph = -45.0 * PI / 180.0;
    l[0] = sin(th) * cos(ph), l[1] = cos(th), l[2] = sin(th) * sin(ph);
}

double ns_closed_form(int k, int normal_mapped, double *lambert)
{
    double l[3], n[3] = {0, 1, 0};
    ns_light_dir(l);
    if (normal_mapped) ns_world_normal(k, n);
    const double nl = n[0] * l[0] + n[1] * l[1] + n[2] * l[2], Nl = l[1];
    if (lambert) *lambert = NS_RHO / PI * NS_E_SUN * fmax(0.0, nl);
    return NS_RHO / PI * NS_E_SUN * Nl * (1 + 2 * nl) / (1 + 2 * Nl);
}

static int write_bytes(const char *dir, const char *name, const void *data, size_t len)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    if (!f) return -1;
    const int ok = fwrite(data, 1, len, f) == len;
    return fclose(f) == 0 && ok ? 0 : -1;
}

int ns_write_png(const char *dir)
{
    uint8_t px[8 * 2 * 3];
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 8; x++) {
            double n[3];
            ns_stripe_normal(x / 2, n);
            for (int c = 0; c < 3; c++) px[3 * (y * 8 + x) + c] = ns_to_byte(n[c]);
        }
    char p[512], err[TL_ERR_LEN];
    snprintf(p, sizeof p, "%s/normal.png", dir);
    return tl_png_write_rgb8(p, 8, 2, px, err);
}

int ns_write_floor_bin(const char *dir, float tangent_w)
{
    const float pos[12] = {-2, 0, 2, 2, 0, 2, 2, 0, -2, -2, 0, -2}, nrm[12] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};
    const float tan[16] = {1, 0, 0, tangent_w, 1, 0, 0, tangent_w, 1, 0, 0, tangent_w, 1, 0, 0, tangent_w};
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    unsigned char b[48 + 48 + 32 + 64 + 12];
    memcpy(b, pos, 48), memcpy(b + 48, nrm, 48), memcpy(b + 96, uv, 32), memcpy(b + 128, tan, 64), memcpy(b + 192, idx, 12);
    return write_bytes(dir, "floor.bin", b, sizeof b);
}

/* The unit quaternion turning −Z (where KHR_lights_punctual points a directional light) to d. */
static void aim(const double d[3], double q[4])
{
    const double a[3] = {0, 0, -1};
    double w = 1 + (a[0] * d[0] + a[1] * d[1] + a[2] * d[2]);
    double x = a[1] * d[2] - a[2] * d[1], y = a[2] * d[0] - a[0] * d[2], z = a[0] * d[1] - a[1] * d[0];
    const double l = sqrt(w * w + x * x + y * y + z * z);
    q[0] = x / l, q[1] = y / l, q[2] = z / l, q[3] = w / l;
}

int ns_write_gltf(const char *dir, const char *name, int tangent, const char *material_extra, const char *node_extra)
{
    return ns_write_gltf_lit(dir, name, tangent, material_extra, node_extra, "lightmap");
}

int ns_write_gltf_lit(const char *dir, const char *name, int tangent, const char *material_extra, const char *node_extra,
                      const char *lighting)
{
    double l[3], d[3], q[4];
    ns_light_dir(l);
    for (int k = 0; k < 3; k++) d[k] = -l[k];
    aim(d, q);
    /* a probe-lit floor alone gives the bake nothing to place probes around: a static wall (the
     * same mesh stood up, facing −x, at x = 6, y in [−2, 2]; its shadow stays beyond x = 4.8)
     * makes the level */
    const int dynamic = strcmp(lighting, "lightmap") != 0;
    char json[4096];
    const int n = snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_lights_punctual\"],"
             "\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"directional\",\"color\":[1,1,1],"
             "\"intensity\":%.17g}]}},"
             "\"scene\":0,\"scenes\":[{\"nodes\":[0,1%s]}],"
             "\"nodes\":[{\"name\":\"floor\",\"mesh\":0,\"extras\":{\"lbk_lighting\":\"%s\"}%s},"
             "{\"name\":\"sun\",\"rotation\":[%.17g,%.17g,%.17g,%.17g],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}%s],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2%s},"
             "\"indices\":4,\"material\":0}]}],"
             "\"materials\":[{\"name\":\"bumpy\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[%.17g,%.17g,%.17g,1],"
             "\"metallicFactor\":0,\"roughnessFactor\":1}%s}],"
             "\"textures\":[{\"source\":0,\"sampler\":0}],\"samplers\":[{\"magFilter\":9728,\"minFilter\":9728}],"
             "\"images\":[{\"uri\":\"normal.png\"}],"
             "\"buffers\":[{\"uri\":\"floor.bin\",\"byteLength\":204}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":192},"
             "{\"buffer\":0,\"byteOffset\":192,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"byteOffset\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
             "\"min\":[-2,0,-2],\"max\":[2,0,2]},"
             "{\"bufferView\":0,\"byteOffset\":48,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":0,\"byteOffset\":96,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
             "{\"bufferView\":0,\"byteOffset\":128,\"componentType\":5126,\"count\":4,\"type\":\"VEC4\"},"
             "{\"bufferView\":1,\"byteOffset\":0,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}]}",
             NS_E_SUN, dynamic ? ",2" : "", lighting, node_extra, q[0], q[1], q[2], q[3],
             dynamic ? ",{\"name\":\"wall\",\"mesh\":0,\"translation\":[6,0,0],\"rotation\":[0,0,0.70710678118654752,0.70710678118654752],\"extras\":{\"lbk_lighting\":\"lightmap\"}}" : "", tangent ? ",\"TANGENT\":3" : "", NS_RHO, NS_RHO, NS_RHO,
             material_extra);
    if (n < 0 || (size_t)n >= sizeof json) return -1;
    return write_bytes(dir, name, json, (size_t)n);
}

int ns_write_all(const char *dir, float tangent_w)
{
    return ns_write_png(dir) || ns_write_floor_bin(dir, tangent_w) || ns_write_gltf(dir, "derived.gltf", 0, NS_NORMAL_TEX, "") ||
                   ns_write_gltf(dir, "authored.gltf", 1, NS_NORMAL_TEX, "") || ns_write_gltf(dir, "flat.gltf", 0, "", "")
               ? -1
               : 0;
}
