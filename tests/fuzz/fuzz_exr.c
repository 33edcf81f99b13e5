/* libFuzzer harness for the sky EXR reader (scene/exr_read.c over OpenEXRCore): each input
 * is written to a file of this process and read with a pixel cap. A crash or sanitizer report is
 * a finding; a refusal is an answer. A read that succeeds must keep the reader's contract
 * (exr_read.h): a non-empty image within the cap, every value finite and >= 0 (negative values
 * clamped, NaN/Inf refused), alpha included. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/exr_read.h"
#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char path[64];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!path[0]) snprintf(path, sizeof path, "/tmp/lbk_fuzz_exr_%ld.exr", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) abort();
    bk_image im;
    memset(&im, 0, sizeof im);
    char err[256];
    if (bk_exr_read(path, 1 << 20, &im, err, sizeof err) == 0) {
        if (im.width <= 0 || im.height <= 0 || !im.rgba || (size_t)im.width * (size_t)im.height > (1u << 20)) abort();
        for (size_t i = 0; i < 4 * (size_t)im.width * (size_t)im.height; i++)
            if (!isfinite(im.rgba[i]) || im.rgba[i] < 0) abort();
        free(im.rgba);
    }
    return 0;
}
