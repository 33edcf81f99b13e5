/* Conversion profiles: what a console-ready pack looks like, as data (tools/convert/profiles/README.md
 * documents the file format). A profile is parsed from text; the built-in ones are ordinary files
 * in tools/convert/profiles/ found through a search path. */
#ifndef LBK_TOOLS_PROFILE_H
#define LBK_TOOLS_PROFILE_H

#include <stddef.h>
#include <stdint.h>

#include "tools/common/image_io.h" /* TL_ERR_LEN */

#define TL_PROFILE_MAX_RULES 32
#define TL_PROFILE_EXT ".profile"

typedef enum tl_ship {
    TL_SHIP_KEEP = 0, /* the section ships */
    TL_SHIP_DROP = 1  /* the section is left out of the pack */
} tl_ship;

typedef struct tl_section_rule {
    uint32_t type;        /* section fourcc; 0 in tl_profile.defaults */
    int ship;             /* tl_ship */
    uint32_t compression; /* lbk_compression */
    int zstd_level;       /* 1..22 when compression is zstd */
} tl_section_rule;

typedef struct tl_profile {
    char name[64];
    char description[256];
    uint32_t alignment;               /* section alignment of the pack, power of two in [16, 65536] */
    tl_section_rule defaults;         /* for every type without its own rule (also unknown types) */
    tl_section_rule rules[TL_PROFILE_MAX_RULES];
    size_t rule_count;
    /* [lmap] texture layout the runtime needs */
    uint32_t lmap_row_pitch_alignment; /* bytes per page row padded to a multiple of this; 0: as baked */
    uint32_t lmap_page_alignment;      /* each page plane starts at a multiple of this; 0: as baked */
    uint32_t lmap_format[2];           /* plane encodings (lbk_lmap_format0/1; spec §9.2); 0, 0: as baked */
    uint32_t lmap_max_page;            /* no page side (after padding) above this; 0: none (the spec's 16384) */
    uint64_t text_hash;                /* XXH3-64 of the profile's text (META convert.profile_hash) */
} tl_profile;

/* Parses profile text. `origin` names the text in error messages ("console-current.profile").
 * Errors say the line number and what was expected. Returns 0 or -1. */
int tl_profile_parse(const char *text, size_t size, const char *origin, tl_profile *out, char err[TL_ERR_LEN]);
/* Reads and parses a profile file. */
int tl_profile_load_file(const char *path, tl_profile *out, char err[TL_ERR_LEN]);
/* NAME_OR_FILE: a path (contains '/' or ends with .profile) is loaded as a file; otherwise
 * NAME.profile is looked up in, in order: each directory of $LBK_PROFILE_PATH (':'-separated), the
 * directory `extra_dir` when non-NULL, <dir of the lbk binary>/../tools/convert/profiles,
 * <dir of the lbk binary>/../share/lbk/profiles and ./tools/convert/profiles. */
int tl_profile_resolve(const char *name_or_file, const char *extra_dir, tl_profile *out, char err[TL_ERR_LEN]);
/* The rule that applies to a section type (its own rule, else the defaults with type set). */
tl_section_rule tl_profile_rule(const tl_profile *profile, uint32_t type);
/* Writes the names of the profiles found on the search path into buf as "a, b, c" (for --help
 * and "unknown profile" errors). */
void tl_profile_list(const char *extra_dir, char *buf, size_t size);

/* "META", "GLG" (trailing spaces trimmed) → fourcc; 0 when not 1–4 printable non-space chars. */
uint32_t tl_fourcc_parse(const char *s);

#endif
