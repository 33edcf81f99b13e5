/* lbk view: a bake in the browser. tl_view_write writes a self-contained folder (index.html, the
 * viewer scripts with three.js, fzstd and hash-wasm vendored from npm, and data.js holding the
 * container and the glTF export of the scene as base64, so the page opens from disk with no
 * server); tl_view_serve serves such a folder over HTTP on 127.0.0.1 only. The page, its reader of
 * the container and what it shows: viewer/README.md. */
#ifndef LBK_TOOLS_VIEW_H
#define LBK_TOOLS_VIEW_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

typedef struct tl_view_options {
    const char *container; /* LEVEL.lbk */
    const char *scene;     /* the .gltf/.glb it was baked from */
    const char *out_dir;   /* created when missing; files of an earlier run are replaced */
    const char *inspect_json; /* optional: `lbk inspect --json` of the container (text), shown in the panel */
    const char *report_path;  /* optional: the bake's `--json-report` file (error against wall-clock time) */
} tl_view_options;

typedef struct tl_view_stats {
    uint32_t files;      /* written into out_dir */
    uint64_t data_bytes; /* of data.js */
    uint32_t astc_pages; /* ASTC lightmap pages the page got as decoded 1.0 texels (it has no ASTC
                            decoder): R11G11B10F + RGBA8 of what astcenc decodes */
} tl_view_stats;

typedef enum tl_view_status {
    TL_VIEW_OK = 0,
    TL_VIEW_IO,      /* a file could not be read or written */
    TL_VIEW_INPUT,   /* not a valid container, or the scene is not the one it was baked from */
    TL_VIEW_INTERNAL /* out of memory */
} tl_view_status;

/* Returns a tl_view_status; err says why when it is not TL_VIEW_OK. */
int tl_view_write(const tl_view_options *options, tl_view_stats *stats, char err[TL_ERR_LEN]);

/* The embedded page files (generated at build time from viewer/: Makefile "viewer assets"). */
typedef struct tl_view_asset {
    const char *path; /* relative, '/'-separated */
    const unsigned char *data;
    size_t size;
} tl_view_asset;
extern const tl_view_asset tl_view_assets[];
extern const size_t tl_view_asset_count;

/* ---- serving (serve.c) --------------------------------------------------------------------- */
/* A listening TCP socket on 127.0.0.1:port (0: any free port; *bound_port says which). Returns the
 * socket, or -1 with err. */
int tl_view_listen(uint16_t port, uint16_t *bound_port, char err[TL_ERR_LEN]);
/* Answers requests on `listen_fd` with files of `dir`, one at a time, until *stop becomes non-zero
 * (checked at least every 200 ms; a signal handler may set it) or, when max_requests > 0, after that
 * many requests. Requests are untrusted: only GET (and HEAD) of paths of [A-Za-z0-9._-/] without a
 * ".." or "." segment, regular files only, symbolic links not followed; a request line or header
 * block over 8 KiB, or one not complete within 5 s, is dropped. Returns 0, or -1 with err when the
 * socket fails. */
int tl_view_serve(int listen_fd, const char *dir, volatile int *stop, unsigned max_requests, char err[TL_ERR_LEN]);

#endif
