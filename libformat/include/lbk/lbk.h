/* liblbk — the light bake kit container library. Depends on libzstd and libxxhash only.
 *
 * API rules (every public header follows them; the style of zstd and OpenEXRCore):
 *
 * Names. lbk_<module>[_<item>]_<verb>, the verb last. The module is the header's concept
 *   (reader, writer, lmap, glg, llg, octp, oct, dls, door, meta, objects, report, sh9, ahd,
 *   tetra, validate, issue). Types lbk_<name>, macros and enumerators LBK_<NAME>. A qualifier
 *   follows the verb: _open_file, _open_memory, _to_file. One spelling per word: half_extents
 *   (three values), centre, axes.
 * Verbs.
 *   _open / _close  acquire and release. An opaque handle (lbk_reader, lbk_writer, lbk_dls_view,
 *                   lbk_door_view, lbk_dls_runtime) is allocated by _open and freed by _close
 *                   (NULL is a no-op). The other section views (lbk_lmap_view, lbk_glg_view,
 *                   lbk_llg_view, lbk_octp_view, lbk_meta_view, lbk_objects_view,
 *                   lbk_report_view) are structs that lbk_<section>_open fills and that point
 *                   into the caller's bytes: there is nothing to close.
 *   _count          the number of items of a handle (struct views carry counts as fields).
 *   _get            (view, index, …, out): item `index` into *out; LBK_ERR_NOT_FOUND past the
 *                   end (also for texel coordinates outside a page).
 *   _find           (view, key, &index): LBK_ERR_NOT_FOUND when absent.
 *   _add            a writer's input.
 *   _build          (desc, allocator, &out, &size): section bytes in one buffer allocated with
 *                   the allocator; free it with lbk_free.
 *   _pack / _unpack values to the bytes of the format and back (lbk_sh9_pack,
 *                   lbk_r11g11b10f_pack); _from_<form> / _to_<form> convert between in-memory
 *                   forms (lbk_ahd_from_linear).
 *   Anything else is named after what it computes: lbk_glg_sample, lbk_sh9_irradiance,
 *   lbk_result_name, lbk_reader_header.
 * Results. Every fallible call returns lbk_result. Codes are never renumbered; new codes are
 *   appended before LBK_RESULT_COUNT_ (which is not part of the ABI), so treat an unknown code
 *   as an error; lbk_result_name names it. Nothing prints, exits or keeps global state; all
 *   memory goes through an optional lbk_allocator; handles are opaque.
 * Size-tagged structs. Every struct the caller hands in for the library to read — options
 *   (lbk_<x>_options, where a NULL pointer means defaults) and descriptions (lbk_<x>_desc) —
 *   has `size_t size` as its first member and means defaults when zero-initialised. Set size
 *   with the LBK_<TYPE>_INIT macro or `.size = sizeof(T)`, and initialise by designator, never
 *   by position. size == 0 is read as the struct's layout in liblbk 1.0, so `= {0}` and memset
 *   callers keep working but do not see fields added later; fields past `size` read as zero;
 *   a non-zero size below the 1.0 layout is LBK_ERR_INVALID_ARGUMENT; a size larger than this
 *   library knows is accepted when the bytes it does not know are zero, else
 *   LBK_ERR_UNSUPPORTED_FEATURE. Structs the library fills (views, infos, stats, issues, check
 *   details), array elements (lbk_lmap_page_desc, lbk_llg_grid_desc, lbk_octp_probe_desc,
 *   lbk_door_desc, lbk_door_state_desc, lbk_dls_set_desc, lbk_dls_sparse, lbk_meta_pair,
 *   lbk_object, lbk_lmuv_primitive_desc, lbk_lmuv_mesh_primitive) and lbk_allocator are frozen
 *   within a major version: growth comes as new functions or structs.
 * Experimental. Declarations under `#ifdef LBK_STATIC_LINKING_ONLY` (the DLS builder's tuning
 *   and statistics) may change in any release; use them only when linking liblbk statically.
 * Versions. LBK_LIBRARY_VERSION_* describe this library's API (semantic versioning; the soname is
 *   liblbk.so.<major>; lbk.pc takes its Version from here); lbk_version_number() and
 *   lbk_version_string() report the library linked at run time. LBK_FORMAT_VERSION_* are the
 *   container format version this library writes and the newest it reads: a separate number.
 * Thread safety. Every header says what holds for its functions. No function keeps hidden
 *   state: two threads may always work on distinct objects.
 *
 * Thread safety of this header: every function is safe to call from any thread. */
#ifndef LBK_LBK_H
#define LBK_LBK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(LBK_BUILDING_SHARED) && defined(__GNUC__)
#define LBK_API __attribute__((visibility("default")))
#else
#define LBK_API
#endif

/* ---- versions ---------------------------------------------------------------------------- */

/* The container format written by this library (spec/container.md §2); it reads every minor
 * version of this major up to LBK_FORMAT_VERSION_MINOR. Not the library's version. */
#define LBK_FORMAT_VERSION_MAJOR 1
/* The newest container minor version this library reads and writes. A writer stamps each file
 * with the lowest minor version that defines everything in it (spec §1.3): 2 when an LMAP page is
 * block-encoded, 1 when it holds LMUV, else 0 (3: an OCTP probe volume, 4: a TERR error map), so a file without newer content keeps the bytes an
 * older writer gave it. */
#define LBK_FORMAT_VERSION_MINOR 4

/* This library's version (semantic versioning of the API and ABI): the minor grows with every
 * release that adds API. 1.1: LMUV; 1.2: block-encoded LMAP pages (BC6H/BC4/BC5 decoding);
 * 1.3: OCTP probe volumes and their sampler; 1.4: the TERR error map, the DLS linear apply and
 * its caller-driven jobs; 1.5: the checks of a container against the glTF the caller loaded,
 * lbk_lmuv_object_check (an LMUV record against its mesh) and lbk_objects_geometry_check (an
 * object's geometry hash against its triangles), and LBK_ERR_MISMATCH. tests/structure/versions.sh
 * keeps it in step with lbk --version, lbk.pc and the spec. */
#define LBK_LIBRARY_VERSION_MAJOR 1
#define LBK_LIBRARY_VERSION_MINOR 5
#define LBK_LIBRARY_VERSION_PATCH 0
#define LBK_LIBRARY_VERSION_NUMBER \
    (LBK_LIBRARY_VERSION_MAJOR * 10000 + LBK_LIBRARY_VERSION_MINOR * 100 + LBK_LIBRARY_VERSION_PATCH)
#define LBK_QUOTE_(x) #x
#define LBK_EXPAND_AND_QUOTE_(x) LBK_QUOTE_(x)
#define LBK_LIBRARY_VERSION_STRING                                                                      \
    LBK_EXPAND_AND_QUOTE_(LBK_LIBRARY_VERSION_MAJOR) "." LBK_EXPAND_AND_QUOTE_(LBK_LIBRARY_VERSION_MINOR) \
    "." LBK_EXPAND_AND_QUOTE_(LBK_LIBRARY_VERSION_PATCH)

/* The version of the library linked at run time (compare with LBK_LIBRARY_VERSION_NUMBER to
 * detect a mismatched liblbk.so): major·10000 + minor·100 + patch, and "major.minor.patch". */
LBK_API unsigned lbk_version_number(void);
LBK_API const char *lbk_version_string(void);

/* ---- results ------------------------------------------------------------------------------ */

typedef enum lbk_result {
    LBK_OK = 0,
    LBK_ERR_INVALID_ARGUMENT,   /* caller passed something the API forbids */
    LBK_ERR_OUT_OF_MEMORY,
    LBK_ERR_IO,                 /* open/read/write/fsync/rename failed; see errno */
    LBK_ERR_NOT_LBK,            /* magic mismatch: not a container, or text-mode damaged */
    LBK_ERR_TRUNCATED,          /* the bytes end before the structure they describe */
    LBK_ERR_UNSUPPORTED_VERSION,/* unknown major version */
    LBK_ERR_UNSUPPORTED_FEATURE,/* unknown required feature flag or required section, or a
                                   size-tagged struct with fields this library does not know */
    LBK_ERR_CORRUPT,            /* a structural rule of spec/container.md is broken */
    LBK_ERR_CHECKSUM,           /* a stored checksum does not match */
    LBK_ERR_DECOMPRESS,         /* zstd failed or decoded to the wrong length */
    LBK_ERR_NOT_FOUND,          /* asked-for section or entry does not exist */
    LBK_ERR_LIMIT,              /* a size exceeds a cap (caller's or the file's) */
    LBK_ERR_RANGE,              /* a value is outside what the encoding can hold */
    LBK_ERR_OVERLAPS,           /* more dynamic-set overlaps than the DLS forms allow */
    LBK_ERR_CANCELLED,          /* the caller's progress callback asked to stop (liblbkbake) */
    LBK_ERR_BAD_INPUT,          /* an input scene is unusable: bad glTF, no light, nothing to bake */
    LBK_ERR_INTERNAL,           /* a failure of the library itself or of a dependency (a bug) */
    LBK_ERR_MISMATCH,           /* the container does not describe the caller's data (the glTF
                                   it was baked from: lbk_lmuv_object_check,
                                   lbk_objects_geometry_check) */
    /* new codes are appended here */
    LBK_RESULT_COUNT_           /* not part of the ABI: grows when codes are added */
} lbk_result;

/* A stable upper-case identifier such as "LBK_ERR_CHECKSUM"; never NULL. */
LBK_API const char *lbk_result_name(lbk_result r);
/* A one-line English description; never NULL. */
LBK_API const char *lbk_result_message(lbk_result r);

/* ---- memory ------------------------------------------------------------------------------ */

/* Optional caller allocator. A NULL pointer or an all-zero struct means malloc/free.
 * alloc must return memory aligned to at least 16 bytes. Frozen (not size-tagged). */
typedef struct lbk_allocator {
    void *(*alloc)(void *user, size_t size);
    void (*free)(void *user, void *ptr);
    void *user;
} lbk_allocator;

/* Frees memory that the library returned through the given allocator (NULL: free). */
LBK_API void lbk_free(const lbk_allocator *allocator, void *ptr);

/* ---- size-tagged structs (the rule above) ------------------------------------------------ */

/* `T x = LBK_SIZED_INIT(T);` gives the defaults with size set; each struct also has its own
 * LBK_<TYPE>_INIT. */
#ifdef __cplusplus
#define LBK_SIZED_INIT(T) {sizeof(T)}
#else
#define LBK_SIZED_INIT(T) {.size = sizeof(T)}
#endif

/* ---- radiometric scale (spec/container.md §5.7) ------------------------------------------
 * Each lighting section (LMAP, GLG, LLG, OCTP) stores one f32 `scale`, a positive normal finite
 * power of two: stored value × scale = physical value (irradiance in lux, radiance in the same
 * units per steradian). The API has it in two places only: `scale` of the section's build desc
 * (lbk_lmap_build_desc, lbk_glg_build_desc, lbk_llg_build_desc, lbk_octp_build_desc; 0 means
 * 1, anything else that is not a valid scale is LBK_ERR_INVALID_ARGUMENT) and `scale` of its
 * view. Encoded data — lbk_ahd_texel codes, R11G11B10F and RGB9E5 words, packed SH9 bytes, DLS
 * payloads (in the scale of their target space's base section) — are in stored units; every
 * float-valued lighting input or output (the SH and irradiance of the build descs, the probe
 * getters, samplers and lbk_lmap_page_irradiance) is physical. Depth moments, directions,
 * visibility and ratios are not scaled. Being a power of two, the scale never changes a
 * rounding: a writer encodes value / scale, a reader multiplies the decoded value. */

/* ---- section types ------------------------------------------------------------------------ */

/* Four-character section type codes, stored little-endian (first char in the lowest byte). */
#define LBK_FOURCC(a, b, c, d) \
    ((uint32_t)(uint8_t)(a) | ((uint32_t)(uint8_t)(b) << 8) | ((uint32_t)(uint8_t)(c) << 16) | ((uint32_t)(uint8_t)(d) << 24))

#define LBK_SECTION_META LBK_FOURCC('M', 'E', 'T', 'A') /* provenance key/values */
#define LBK_SECTION_REPT LBK_FOURCC('R', 'E', 'P', 'T') /* bake report: error vs time */
#define LBK_SECTION_OBJS LBK_FOURCC('O', 'B', 'J', 'S') /* object table */
#define LBK_SECTION_LMAP LBK_FOURCC('L', 'M', 'A', 'P') /* AHD lightmap atlas pages */
#define LBK_SECTION_GLG  LBK_FOURCC('G', 'L', 'G', ' ') /* global light grid */
#define LBK_SECTION_LLG  LBK_FOURCC('L', 'L', 'G', ' ') /* local light grids */
#define LBK_SECTION_DLS  LBK_FOURCC('D', 'L', 'S', ' ') /* dynamic light sets + clusters */
#define LBK_SECTION_DOOR LBK_FOURCC('D', 'O', 'O', 'R') /* interactive elements */
#define LBK_SECTION_OCTP LBK_FOURCC('O', 'C', 'T', 'P') /* octahedral probes (GIBS style) */
#define LBK_SECTION_LMUV LBK_FOURCC('L', 'M', 'U', 'V') /* lightmap coordinates per object (1.1) */

/* Writes the 4 characters of a type code plus a NUL into out[5]; non-printable bytes become '?'. */
LBK_API void lbk_fourcc_string(uint32_t type, char out[5]);

/* A byte string that is not NUL-terminated: views into a container point at its string blobs. */
typedef struct lbk_string {
    const char *data;
    size_t size;
} lbk_string;

/* XXH3-64 (seed 0) of a byte range: the hash the format uses for checksums and provenance. */
LBK_API uint64_t lbk_hash64(const void *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif
