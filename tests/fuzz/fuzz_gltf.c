/* libFuzzer harness for the glTF importer (scene/gltf_*.cc: tinygltf, Draco, stb_image,
 * our own JSON pre-pass and limits): each input is written to a file of this process
 * (`.glb` when it starts with the GLB magic, else `.gltf`) in a private folder and imported with
 * small caps, so that no input can make the harness allocate or run without bound. Any crash or
 * sanitizer report is a finding; an import error is an answer. Buffers and images that the
 * input names by URI resolve inside that folder (the resource policy): a seed may bring none. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/import.h"
#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char folder[64];

static void quiet(void *user, const char *msg) { (void)user, (void)msg; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!folder[0]) {
        snprintf(folder, sizeof folder, "/tmp/lbk_fuzz_gltf_XXXXXX");
        if (!mkdtemp(folder)) abort();
    }
    const int glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
    char path[128];
    snprintf(path, sizeof path, "%s/in%s", folder, glb ? ".glb" : ".gltf");
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) abort();
    bk_import_options o;
    memset(&o, 0, sizeof o);
    o.max_triangles = 1 << 16;
    o.max_file_bytes = 1 << 22;
    o.max_json_bytes = 1 << 20;
    o.max_image_bytes = 1 << 24;
    o.max_texture_size = 64;
    o.max_sky_size = 64;
    o.max_image_pixels = 1 << 20;
    o.warn = quiet;
    o.normal_maps = (int)(size & 1); /* both imports: the bake's, and the renderer's with normal maps */
    bk_scene s;
    memset(&s, 0, sizeof s);
    char err[256];
    if (bk_import_gltf(path, &o, &s, err, sizeof err) == 0) bk_scene_free(&s);
    return 0;
}
