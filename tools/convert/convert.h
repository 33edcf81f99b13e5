/* Repacking a container with a profile (lbk convert). The CLI is cmd_convert.c; this is the logic,
 * callable from tests without going through files. */
#ifndef LBK_TOOLS_CONVERT_H
#define LBK_TOOLS_CONVERT_H

#include <stddef.h>
#include <stdint.h>

#include "tools/convert/pack_error.h"
#include "tools/convert/profile.h"
#include "lbk/container.h"

typedef enum tl_convert_status {
    TL_CONVERT_OK = 0,
    TL_CONVERT_BAD_INPUT,  /* the input container is invalid or unreadable */
    TL_CONVERT_BAD_EXR,    /* --from-exr: a page file is missing, has the wrong size or bad values */
    TL_CONVERT_UNSUPPORTED,/* the profile asks for something this input cannot do */
    TL_CONVERT_IO,         /* reading or writing a file failed */
    TL_CONVERT_INTERNAL    /* out of memory, or the output failed validation (a bug) */
} tl_convert_status;

typedef struct tl_convert_section {
    uint32_t type;
    int dropped;
    uint32_t compression;   /* in the output */
    uint64_t in_stored, in_decoded;
    uint64_t out_stored, out_decoded;
    int relaid;             /* the payload was rewritten (LMAP layout or --from-exr pages) */
} tl_convert_section;

typedef struct tl_convert_report {
    tl_convert_section sections[LBK_MAX_SECTIONS];
    uint32_t section_count;
    uint64_t in_size, out_size;
    uint32_t pages_imported; /* --from-exr */
    double encode_seconds;   /* block-encoding the lightmap pages (wall clock) */
    int pack_error_computed; /* options.pack_error was filled in */
    char pack_error_skipped[TL_ERR_LEN]; /* why it could not be (the pack is written all the same:
                                            e.g. the two decoded containers past memory), or "" */
} tl_convert_report;

typedef struct tl_convert_options {
    const tl_profile *profile;
    const char *from_exr_dir; /* NULL: no import */
    uint64_t max_decoded_bytes; /* cap on the input's decoded sections (--max-memory); 0: liblbk's */
    /* When non-NULL: the error of the pack's lightmap against the input's (pack_error.h), from
     * decoding what was just encoded; filled in when both have one and no pages were imported
     * (an edit is not an error), report->pack_error_computed says. Free with tl_pack_error_free. */
    tl_pack_error *pack_error;
} tl_convert_options;

/* Converts a container held in memory. *out is malloc'ed (free()). The output is validated before
 * it is returned. `report` may be NULL. */
tl_convert_status tl_convert_memory(const void *in, size_t in_size, const tl_convert_options *options, void **out,
                                    size_t *out_size, tl_convert_report *report, char err[TL_ERR_LEN]);

#endif
