/* The DLS runtime's state, shared by dls_apply.c (API, weights, jobs), dls_plan.c (chunks, texel
 * planes) and dls_dirty.c (changed regions). Private. */
#ifndef LBK_DLS_RUNTIME_H
#define LBK_DLS_RUNTIME_H

#include "dls_format.h"
#include "dls_kernel.h"

typedef struct rt_cluster {
    uint32_t form, space, k, nsets, run_count, subgroup_count, target_count;
    uint32_t set_first; /* its sets' weights start at runtime->cw[set_first] */
    const uint8_t *sets, *runs, *subgroups, *words, *bases, *slots, *payload;
    uint32_t entry_count;
    /* linear mode: the prepared floats (dls_linear.c). Plane p of the base at lin + p·stride
     * (target ordinal o at + o·f); fixed forms: slot j's plane p at lin + (planes·(1 + j) + p)·stride;
     * prefix forms: plane p's entries at lin + planes·stride + p·estride (entry e at + e·f). */
    float *lin;
    uint64_t stride, estride;
} rt_cluster;

/* Where texels live: one plane pair per LMAP page, or one pseudo page spanning the whole index
 * space for the four-array form of the desc. */
typedef struct rt_plane {
    uint64_t first, width, height;
    const uint8_t *base0, *base1;
    uint8_t *out0, *out1;
    size_t bp0, bp1, op0, op1; /* row pitches in bytes */
    float *lo[3];              /* linear mode: the output planes (dls_linear.c) */
    size_t lp[3];              /* their row pitches in bytes */
    bool packed;               /* every pitch is 4·width: the page is one contiguous stretch */
} rt_plane;

#define RT_GAP 0xFFFFFFFFu

/* A job: `count` targets of one cluster from cluster-order position `ordinal` (starting `skip`
 * targets into its run `run`; packed clusters: whole sub-groups from `subgroup`), or, for
 * cluster == RT_GAP, the targets [ordinal, ordinal + count) of `space` that no cluster has. */
typedef struct rt_chunk {
    uint32_t cluster, space, run, skip, subgroup, count;
    uint64_t ordinal, entry; /* entry: offset of the first target's entries within the cluster */
    uint32_t piece_first, piece_count;
} rt_chunk;

/* A region a chunk writes: a range of target indices, and for texels with pages the bounding
 * rectangle of the chunk's targets on one page (page == RT_GAP: no rectangle). */
typedef struct rt_piece {
    uint64_t first, count;
    uint32_t page;
    lbk_dls_rect rect;
} rt_piece;

enum { RT_SKIP = 0, RT_COPY = 1, RT_APPLY = 2 };

struct lbk_dls_runtime {
    lbk_allocator alloc_copy;
    const lbk_allocator *alloc;
    lbk_dls_runtime_desc desc;
    lbk_dls_raw raw;
    const dls_kernels *kern;
    uint32_t nsets, ndoors;
    uint8_t *kinds;
    uint32_t *member_offset, *members;
    uint32_t *door_of_set; /* kind 1/2 sets named by a door: the door; else LBK_DLS_NO_SET */
    uint32_t ncl;
    rt_cluster *cl;
    bool space_on[LBK_DLS_SPACE_COUNT_];
    const uint8_t *probe_base[LBK_DLS_SPACE_COUNT_];
    uint8_t *probe_out[LBK_DLS_SPACE_COUNT_];
    bool linear;                              /* LBK_DLS_RUNTIME_LINEAR */
    float *probe_lin[LBK_DLS_SPACE_COUNT_];   /* linear mode: 27 floats per probe */
    void *lin_block;                          /* the prepared floats of every cluster */
    uint64_t lin_bytes;
    uint32_t nplanes, npages; /* npages: the desc's pages (0 for the array form) */
    rt_plane *planes;
    uint32_t nchunks, npieces;
    rt_chunk *chunks;
    rt_piece *pieces;
    /* per apply */
    float *w, *last, *cw; /* effective weights, those of the last apply, per-cluster weights */
    uint8_t *changed, *action;
    uint32_t *jobs, njobs;
    int in_apply, valid, full;
    lbk_dls_apply_stats stats;
    /* what the last apply wrote */
    uint32_t nranges[LBK_DLS_SPACE_COUNT_];
    lbk_dls_range *ranges[LBK_DLS_SPACE_COUNT_]; /* LBK_DLS_DIRTY_RANGES each */
    uint32_t *nrects;                            /* per page */
    lbk_dls_rect *rects;                         /* LBK_DLS_DIRTY_RECTS per page */
};

/* dls_plan.c: texel planes from the desc, the chunk table with each chunk's pieces, and the
 * work of one chunk. */
lbk_result rt_planes_make(lbk_dls_runtime *r);
lbk_result rt_chunks_make(lbk_dls_runtime *r);
void rt_chunk_run(const lbk_dls_runtime *r, const rt_chunk *ch);
/* Calls fn for each stretch of consecutive target indices of the chunk, in cluster order. */
typedef void (*rt_span_fn)(void *ctx, uint64_t start, uint32_t len);
void rt_chunk_spans(const lbk_dls_runtime *r, const rt_chunk *ch, rt_span_fn fn, void *ctx);

/* The longest stretch from texel t (at most len) that is contiguous in all planes, and its
 * addresses (byte outputs in byte mode, linear ones in linear mode; the others NULL). */
typedef struct texel_seg {
    uint32_t len, plane;
    uint64_t x, y;
    const uint8_t *b0, *b1;
    uint8_t *o0, *o1;
    float *l[3];
} texel_seg;
void rt_texel_span(const lbk_dls_runtime *r, uint64_t t, uint64_t len, uint32_t *hint, texel_seg *s);

/* dls_linear.c: the linear mode's prepared data (at open) and the work of one chunk. */
lbk_result rt_linear_prepare(lbk_dls_runtime *r);
void rt_linear_chunk_run(const lbk_dls_runtime *r, const rt_chunk *ch);

/* dls_dirty.c: the changed regions of the jobs of the apply that just ended. */
lbk_result rt_dirty_alloc(lbk_dls_runtime *r);
/* Merges sorted ranges that overlap or touch, then closes all but the cap − 1 widest gaps
 * (cap ≤ LBK_DLS_DIRTY_RANGES); returns the new count. */
uint32_t rt_ranges_merge(lbk_dls_range *v, uint32_t n, uint32_t cap);
void rt_dirty_collect(lbk_dls_runtime *r);

#endif
