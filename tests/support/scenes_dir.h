/* Where the tests and benches find the glTF scenes they read (cornell_box, cornell_box_bjs,
 * room_with_doors, lights_punctual_lamp, water_bottle_draco; scenes/SOURCES.md): the scenes/
 * folder of this repository, as tests and benches run from the repository root. $LBK_SCENES,
 * when set and not empty, overrides it (another copy of the same files).
 *
 * A missing scene is a failure that names the missing file, never a skip: the files are in the
 * repository, so a missing one means a broken checkout or a wrong $LBK_SCENES.
 *
 * Header only (static inline), so the benches that #include support .c files need nothing else. */
#ifndef SD_SCENES_DIR_H
#define SD_SCENES_DIR_H

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* The scenes directory: $LBK_SCENES, else "scenes" (relative to the repository root). */
static inline const char *sd_dir(void)
{
    const char *d = getenv("LBK_SCENES");
    return d && *d ? d : "scenes";
}

/* "<scenes directory>/<rel>" into buf (n bytes); returns buf. */
static inline char *sd_path(char *buf, size_t n, const char *rel)
{
    snprintf(buf, n, "%s/%s", sd_dir(), rel);
    return buf;
}

/* 1 when path can be read; else prints which input is missing (stderr) and returns 0. */
static inline int sd_present(const char *path)
{
    if (access(path, R_OK) == 0) return 1;
    fprintf(stderr, "missing input: %s (the test scenes are in scenes/ of the repository, "
                    "or under $LBK_SCENES when set; LBK_SCENES=%s)\n",
            path, getenv("LBK_SCENES") ? getenv("LBK_SCENES") : "(unset)");
    fflush(stderr);
    return 0;
}

/* For cmocka tests: fails the running test, naming the file, when path cannot be read. */
#define SD_REQUIRE(path)                                                                            \
    do {                                                                                            \
        const char *sd_p_ = (path);                                                                 \
        if (!sd_present(sd_p_)) fail_msg("missing input %s", sd_p_);                                \
    } while (0)

#endif
