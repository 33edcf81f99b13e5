/* Byte layout of the DLS and DOOR sections (spec/container.md §12, §13). Private. */
#ifndef LBK_DLS_FORMAT_H
#define LBK_DLS_FORMAT_H

#include "internal.h"
#include "lbk/dls.h"

/* ---- DLS header (96 bytes): counts of every array, then the target space sizes ------------ */
#define DLS_HEADER_SIZE 96u
enum {
    DLS_H_SET_COUNT = 0,
    DLS_H_LIGHT_REF_COUNT = 4,
    DLS_H_MEMBER_COUNT = 8,
    DLS_H_CLUSTER_COUNT = 12,
    DLS_H_CLUSTER_SET_COUNT = 16,
    DLS_H_RUN_COUNT = 20,
    DLS_H_SUBGROUP_COUNT = 24,
    DLS_H_PREFIX_WORD_COUNT = 28,
    DLS_H_BASE16_COUNT = 32,
    DLS_H_BASE32_COUNT = 36,
    DLS_H_SLOT_COUNT = 40,          /* u64 */
    DLS_H_TEXEL_ENTRY_COUNT = 48,   /* u64 */
    DLS_H_PROBE_ENTRY_COUNT = 56,   /* u64 */
    DLS_H_STRING_BYTES = 64,        /* u64 */
    DLS_H_TARGET_COUNT = 72         /* u64 × 3: texels, GLG probes, LLG probes */
};

/* The arrays follow the header in this order, each at the next multiple of 16 (the order of the
 * public lbk_dls_array too). */
enum {
    DLS_A_SETS,
    DLS_A_LIGHT_REFS,
    DLS_A_MEMBERS,
    DLS_A_CLUSTERS,
    DLS_A_CLUSTER_SETS,
    DLS_A_RUNS,
    DLS_A_SUBGROUPS,
    DLS_A_PREFIX_WORDS,
    DLS_A_BASE16,
    DLS_A_BASE32,
    DLS_A_SLOTS,
    DLS_A_TEXEL_ENTRIES,
    DLS_A_PROBE_ENTRIES,
    DLS_A_STRINGS,
    DLS_A_COUNT
};

#define DLS_SET_SIZE 32u
enum { DLS_S_NAME_OFF = 0, DLS_S_NAME_LEN = 4, DLS_S_KIND = 8, DLS_S_LIGHT_FIRST = 12, DLS_S_LIGHT_COUNT = 16,
       DLS_S_MEMBER_FIRST = 20, DLS_S_MEMBER_COUNT = 24, DLS_S_RESERVED = 28 };
#define DLS_LIGHT_REF_SIZE 8u
#define DLS_CLUSTER_SIZE 64u
enum { DLS_C_FORM = 0, DLS_C_SPACE = 4, DLS_C_OVERLAPS = 8, DLS_C_SET_FIRST = 12, DLS_C_SET_COUNT = 16,
       DLS_C_RUN_FIRST = 20, DLS_C_RUN_COUNT = 24, DLS_C_TARGET_COUNT = 28, DLS_C_AUX_FIRST = 32,
       DLS_C_AUX_COUNT = 36, DLS_C_BASE_FIRST = 40, DLS_C_ENTRY_COUNT = 44, DLS_C_ENTRY_FIRST = 48 /* u64 */,
       DLS_C_SLOT_FIRST = 56 /* u64 */ };
#define DLS_RUN_SIZE 8u
#define DLS_SUBGROUP_SIZE 16u
enum { DLS_G_RUN_FIRST = 0, DLS_G_RUN_COUNT = 4, DLS_G_TARGET_FIRST = 8, DLS_G_SLOTS = 12 };

/* Prefix forms: field width, fields per u32 word, count bias, targets per base, base width. */
typedef struct dls_prefix_form {
    uint32_t bits, per_word, bias, batch, base_bytes;
    uint64_t max_entries;
} dls_prefix_form;

static inline const dls_prefix_form *dls_prefix(uint32_t form)
{
    static const dls_prefix_form forms[3] = {
        {2, 16, 5, 16, 2, 65535u},
        {3, 10, 9, 8, 2, 65535u},
        {8, 4, 17, 16, 4, 0xFFFFFFFFu},
    };
    return form >= LBK_DLS_FORM_PREFIX2 && form <= LBK_DLS_FORM_PREFIX8 ? &forms[form - LBK_DLS_FORM_PREFIX2] : NULL;
}

static inline uint32_t dls_prefix_field(const uint8_t *words, const dls_prefix_form *pf, uint64_t i)
{
    uint32_t w = lbk_rd32(words + 4 * (i / pf->per_word));
    return (w >> (pf->bits * (uint32_t)(i % pf->per_word))) & ((1u << pf->bits) - 1u);
}

static inline uint32_t dls_payload_size(uint32_t space)
{
    return space == LBK_DLS_SPACE_TEXEL ? LBK_DLS_TEXEL_PAYLOAD : LBK_DLS_PROBE_PAYLOAD;
}

/* Array offsets and the section size implied by the header counts; false on overflow. */
typedef struct dls_layout {
    uint64_t count[DLS_A_COUNT];
    uint64_t offset[DLS_A_COUNT];
    uint64_t size; /* align16(end of strings) */
} dls_layout;

static inline bool dls_layout_compute(dls_layout *l)
{
    static const uint32_t elem[DLS_A_COUNT] = {DLS_SET_SIZE, DLS_LIGHT_REF_SIZE, 4, DLS_CLUSTER_SIZE, 4,
                                               DLS_RUN_SIZE, DLS_SUBGROUP_SIZE, 4, 2, 4, 1,
                                               LBK_DLS_TEXEL_PAYLOAD, LBK_DLS_PROBE_PAYLOAD, 1};
    uint64_t at = DLS_HEADER_SIZE;
    for (int a = 0; a < DLS_A_COUNT; a++) {
        if (at > UINT64_MAX - 15) return false;
        at = lbk_align_up(at, 16);
        l->offset[a] = at;
        if (!lbk_madd_u64(at, l->count[a], elem[a], &at)) return false;
    }
    if (at > UINT64_MAX - 15) return false;
    l->size = lbk_align_up(at, 16);
    return true;
}

static inline void dls_layout_from_header(const uint8_t *h, dls_layout *l)
{
    l->count[DLS_A_SETS] = lbk_rd32(h + DLS_H_SET_COUNT);
    l->count[DLS_A_LIGHT_REFS] = lbk_rd32(h + DLS_H_LIGHT_REF_COUNT);
    l->count[DLS_A_MEMBERS] = lbk_rd32(h + DLS_H_MEMBER_COUNT);
    l->count[DLS_A_CLUSTERS] = lbk_rd32(h + DLS_H_CLUSTER_COUNT);
    l->count[DLS_A_CLUSTER_SETS] = lbk_rd32(h + DLS_H_CLUSTER_SET_COUNT);
    l->count[DLS_A_RUNS] = lbk_rd32(h + DLS_H_RUN_COUNT);
    l->count[DLS_A_SUBGROUPS] = lbk_rd32(h + DLS_H_SUBGROUP_COUNT);
    l->count[DLS_A_PREFIX_WORDS] = lbk_rd32(h + DLS_H_PREFIX_WORD_COUNT);
    l->count[DLS_A_BASE16] = lbk_rd32(h + DLS_H_BASE16_COUNT);
    l->count[DLS_A_BASE32] = lbk_rd32(h + DLS_H_BASE32_COUNT);
    l->count[DLS_A_SLOTS] = lbk_rd64(h + DLS_H_SLOT_COUNT);
    l->count[DLS_A_TEXEL_ENTRIES] = lbk_rd64(h + DLS_H_TEXEL_ENTRY_COUNT);
    l->count[DLS_A_PROBE_ENTRIES] = lbk_rd64(h + DLS_H_PROBE_ENTRY_COUNT);
    l->count[DLS_A_STRINGS] = lbk_rd64(h + DLS_H_STRING_BYTES);
}

/* ---- DOOR (spec §13) ------------------------------------------------------------------------ */
#define DOOR_HEADER_SIZE 32u
enum { DOOR_H_ELEMENT_COUNT = 0, DOOR_H_STATE_COUNT = 4, DOOR_H_STATE_MEMBER_COUNT = 8, DOOR_H_RESERVED0 = 12,
       DOOR_H_STRING_BYTES = 16 /* u64 */, DOOR_H_RESERVED1 = 24 /* u64 */ };
#define DOOR_ELEMENT_SIZE 80u
enum { DOOR_E_NAME_OFF = 0, DOOR_E_NAME_LEN = 4, DOOR_E_CENTRE = 8, DOOR_E_AXES = 20, DOOR_E_HALF = 56,
       DOOR_E_OPEN_SET = 68, DOOR_E_CLOSED_SET = 72, DOOR_E_RESERVED = 76 };
#define DOOR_STATE_SIZE 16u
enum { DOOR_S_MEMBER_FIRST = 0, DOOR_S_MEMBER_COUNT = 4, DOOR_S_SET = 8, DOOR_S_RESERVED = 12 };

/* ---- helpers shared by dls.c and door.c ---------------------------------------------------- */
/* Is [off, off+len) a valid string of a blob of blob_size bytes: in range, no NUL, UTF-8? */
bool lbk_dls_string_ok(const uint8_t *blob, uint64_t blob_size, uint32_t off, uint32_t len);

/* Raw access to the arrays of a section lbk_dls_open accepted (for the runtime). */
typedef struct lbk_dls_raw {
    const uint8_t *d;
    uint64_t size;
    uint64_t offset[DLS_A_COUNT];
    uint64_t count[DLS_A_COUNT];
    uint64_t target_count[LBK_DLS_SPACE_COUNT_];
} lbk_dls_raw;
void lbk_dls_view_raw(const lbk_dls_view *view, lbk_dls_raw *raw);

#endif
