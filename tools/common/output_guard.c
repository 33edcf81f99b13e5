/* The one output policy of every lbk command (output_guard.h). */
#include "tools/common/output_guard.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "scene/import.h"

static const tl_guard *active_guard;

void tl_guard_activate(const tl_guard *g) { active_guard = g; }

int tl_guard_check_active(const char *path, char err[TL_ERR_LEN])
{
    return active_guard ? tl_guard_output(active_guard, path, "output", err) : 0;
}

void tl_guard_init(tl_guard *g, const char *cmd)
{
    memset(g, 0, sizeof *g);
    g->cmd = cmd;
}

void tl_guard_free(tl_guard *g)
{
    free(g->inputs);
    memset(g, 0, sizeof *g);
}

static int add_file(tl_guard *g, const struct stat *st, const char *what)
{
    for (size_t i = 0; i < g->count; i++)
        if (g->inputs[i].dev == st->st_dev && g->inputs[i].ino == st->st_ino) return 0;
    if (g->count == g->cap) {
        size_t cap = g->cap ? g->cap * 2 : 8;
        tl_guard_file *v = realloc(g->inputs, cap * sizeof *v);
        if (!v) return -1;
        g->inputs = v;
        g->cap = cap;
    }
    tl_guard_file *f = &g->inputs[g->count++];
    f->dev = st->st_dev;
    f->ino = st->st_ino;
    snprintf(f->what, sizeof f->what, "%s", what);
    return 0;
}

int tl_guard_input(tl_guard *g, const char *path, const char *role)
{
    struct stat st;
    if (!path || !path[0] || stat(path, &st) != 0) return 0;
    char what[96];
    snprintf(what, sizeof what, "%s %s", role, path);
    return add_file(g, &st, what);
}

int tl_guard_input_dir(tl_guard *g, const char *dir, const char *role)
{
    DIR *d = dir ? opendir(dir) : NULL;
    if (!d) return 0;
    char path[4096 + 256];
    int rc = 0;
    for (struct dirent *e; rc == 0 && (e = readdir(d));) {
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat st;
        if (stat(path, &st) == 0 && S_ISREG(st.st_mode)) rc = tl_guard_input(g, path, role);
    }
    closedir(d);
    return rc;
}

/* The folder part of `path` with its trailing '/', or "" for a bare name. */
static void folder_of(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    size_t n = slash ? (size_t)(slash - path) + 1 : 0;
    if (n >= size) n = 0;
    memcpy(dir, path, n);
    dir[n] = 0;
}

int tl_guard_scene(tl_guard *g, const char *scene, const char *allow_outside)
{
    if (tl_guard_input(g, scene, "the scene") != 0) return -1;
    bk_import_options opt;
    memset(&opt, 0, sizeof opt);
    opt.allow_outside = allow_outside;
    bk_scene s;
    char err[256];
    /* the importer names every file it read, resolved the way the bake resolves them */
    if (bk_import_gltf(scene, &opt, &s, err, sizeof err) != 0) return 0;
    char dir[4096], path[4096 + 256], what[96];
    folder_of(scene, dir, sizeof dir);
    int rc = 0;
    for (size_t i = 0; i < s.input_count && rc == 0; i++) {
        const bk_input_file *f = &s.inputs[i];
        if (!strcmp(f->role, "scene")) continue;
        snprintf(path, sizeof path, "%s%s", f->path[0] == '/' ? "" : dir, f->path);
        snprintf(what, sizeof what, "the scene's %s", f->role);
        rc = tl_guard_input(g, path, what);
    }
    bk_scene_free(&s);
    return rc;
}

static const char *kind_of(mode_t m)
{
    return S_ISDIR(m) ? "a directory" : S_ISCHR(m) ? "a character device" : S_ISBLK(m) ? "a block device"
         : S_ISFIFO(m) ? "a FIFO" : S_ISSOCK(m) ? "a socket" : "not a regular file";
}

int tl_guard_replaceable(const char *path, char err[TL_ERR_LEN])
{
    struct stat st;
    if (lstat(path, &st) != 0 || S_ISREG(st.st_mode) || S_ISLNK(st.st_mode)) return 0;
    snprintf(err, TL_ERR_LEN, "%s is %s: lbk replaces only regular files", path, kind_of(st.st_mode));
    return -1;
}

int tl_guard_output(const tl_guard *g, const char *path, const char *what, char err[TL_ERR_LEN])
{
    size_t n = path ? strlen(path) : 0;
    if (!n) {
        snprintf(err, TL_ERR_LEN, "%s: an empty path", what);
        return -1;
    }
    if (path[n - 1] == '/') {
        snprintf(err, TL_ERR_LEN, "%s %s names a folder: give a file name", what, path);
        return -1;
    }
    struct stat st;
    if (stat(path, &st) != 0) {
        /* nothing there yet, or a dangling symlink, whose rename replaces the link alone */
        if (errno == ENOENT) return 0;
        snprintf(err, TL_ERR_LEN, "%s %s: %s", what, path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, TL_ERR_LEN, "%s %s is %s: lbk replaces only regular files", what, path, kind_of(st.st_mode));
        return -1;
    }
    for (size_t i = 0; g && i < g->count; i++)
        if (g->inputs[i].dev == st.st_dev && g->inputs[i].ino == st.st_ino) {
            snprintf(err, TL_ERR_LEN, "%s %s is %s, which this command reads: refusing to overwrite an input", what,
                     path, g->inputs[i].what);
            return -1;
        }
    return 0; /* a regular file: what the atomic writers replace */
}

int tl_guard_output_dir(const tl_guard *g, const char *dir, const char *const *names, const char *what,
                        char err[TL_ERR_LEN])
{
    struct stat st;
    if (stat(dir, &st) == 0 && !S_ISDIR(st.st_mode)) {
        snprintf(err, TL_ERR_LEN, "%s %s is %s, not a folder", what, dir, kind_of(st.st_mode));
        return -1;
    }
    char path[4096];
    for (size_t i = 0; names && names[i]; i++) {
        size_t n = strlen(dir);
        snprintf(path, sizeof path, "%s%s%s", dir, n && dir[n - 1] == '/' ? "" : "/", names[i]);
        if (tl_guard_output(g, path, what, err) != 0) return -1;
    }
    return 0;
}
