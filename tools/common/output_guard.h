/* The one output policy of every lbk command: an output path may name a regular file or nothing
 * yet, never a device, FIFO, socket or directory (as root, replacing /dev/null with a file would
 * break the machine), and never one of the files the command reads (the container, the scene,
 * its buffers and images, the sky EXR, a profile), whichever name reaches it: the same inode
 * through a hard link, a symlink or `./` is the same file.
 *
 * A command collects its inputs first (tl_guard_input, tl_guard_scene), then checks each output
 * before it writes anything (tl_guard_output, tl_guard_output_dir for a folder whose files it
 * names). The atomic writers check again just before their rename (tl_guard_replaceable), so a
 * path that became a device in between is still refused. */
#ifndef LBK_TOOLS_OUTPUT_GUARD_H
#define LBK_TOOLS_OUTPUT_GUARD_H

#include <stddef.h>
#include <sys/types.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

typedef struct tl_guard_file {
    dev_t dev;
    ino_t ino;
    char what[96]; /* "the container a.lbk", "the scene's buffer b.bin" */
} tl_guard_file;

typedef struct tl_guard {
    tl_guard_file *inputs;
    size_t count, cap;
    const char *cmd; /* for messages: "lbk render" */
} tl_guard;

/* Zero-initialised guard for `cmd` (the string must outlive the guard). */
void tl_guard_init(tl_guard *g, const char *cmd);
void tl_guard_free(tl_guard *g);

/* Records the file at `path` (followed through symlinks) as an input described by `role`
 * ("the container", "the profile"). A path that does not exist is no input: nothing is recorded.
 * Returns 0, or -1 on out of memory. */
int tl_guard_input(tl_guard *g, const char *path, const char *role);

/* Records every regular file directly in `dir` (NULL or missing: nothing) as an input. */
int tl_guard_input_dir(tl_guard *g, const char *dir, const char *role);

/* Records a glTF scene and every file it references (buffers, images, the lbk_sky EXR), as the
 * importer resolves them (allow_outside: a folder the scene may also read from, or NULL). A scene
 * that cannot be read records itself only: the command's own import then reports why.
 * Returns 0, or -1 on out of memory. */
int tl_guard_scene(tl_guard *g, const char *scene, const char *allow_outside);

/* 0 when `path` may be written as the output `what` ("-o", "--png"); else -1 with the reason in
 * err: a non-regular file (named by kind), a path ending in '/', or one of the recorded inputs. */
int tl_guard_output(const tl_guard *g, const char *path, const char *what, char err[TL_ERR_LEN]);

/* For a folder whose files the command writes (`lbk view --out DIR`, `lbk export --exr DIR`): the
 * folder must be a directory or not exist yet, and each named file in it (names: NULL-terminated)
 * must pass tl_guard_output. */
int tl_guard_output_dir(const tl_guard *g, const char *dir, const char *const *names, const char *what,
                        char err[TL_ERR_LEN]);

/* Every file the tools write goes through tl_write_file_atomic; once a command activates its
 * guard, that writer refuses any path tl_guard_output refuses, so files a command names itself
 * inside an output folder (export's pages, view's page) can never replace an input either. This
 * is the tools' one piece of process state: the CLI activates a guard for the command it runs
 * and deactivates it (NULL) before the guard is freed. */
void tl_guard_activate(const tl_guard *g);
/* tl_guard_output against the active guard (0 when none is active). */
int tl_guard_check_active(const char *path, char err[TL_ERR_LEN]);

/* The last check of an atomic writer, just before it renames its temporary file over `path`: 0
 * when path does not exist, is a regular file or a symlink (the rename replaces the link, never
 * what it points to); else -1 with the reason in err. */
int tl_guard_replaceable(const char *path, char err[TL_ERR_LEN]);

#endif
