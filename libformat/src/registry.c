/* The registry of validation issues: one row per stable ID, mirrored in spec/validation.md.
 *
 * Rules for every editor:
 *   - IDs are stable and never reused; a retired check keeps its row with "(retired)" in the text.
 *   - Rows stay sorted by ID (a test checks this); add rows only inside your own block.
 *   - Severity: FATAL = nothing further can be read; ERROR = the file is invalid;
 *     WARNING = the file is valid but something is unusual.
 *   - `section` is the fourcc the issue belongs to (0 for header and section-table issues).
 *   - The message is the generic text; the issue a validator reports carries the values. */
#include "internal.h"

#define FATAL LBK_SEVERITY_FATAL
#define ERROR LBK_SEVERITY_ERROR
#define WARNING LBK_SEVERITY_WARNING

typedef struct issue_row {
    uint32_t id;
    lbk_severity severity;
    uint32_t section;
    const char *message;
} issue_row;

static const issue_row registry[] = {
    /* ---- 100–199 header (container helper) ----------------------------------------------- */
    {100, FATAL, 0, "file is shorter than the 64-byte header"},
    {101, FATAL, 0, "magic mismatch: not an lbk container"},
    {102, FATAL, 0, "magic damaged by a text-mode or 7-bit transfer"},
    {103, FATAL, 0, "unsupported major version"},
    {104, FATAL, 0, "header checksum mismatch"},
    {105, FATAL, 0, "header_size is not 64"},
    {106, FATAL, 0, "file is shorter than header file_size (truncated)"},
    {107, FATAL, 0, "file is longer than header file_size (bytes appended)"},
    {108, FATAL, 0, "unknown required feature bits"},
    {109, WARNING, 0, "unknown optional feature bits (ignored)"},
    {110, FATAL, 0, "section_count outside 1..64"},
    {111, FATAL, 0, "section_alignment is not a power of two in 16..65536"},
    {112, FATAL, 0, "section_table_offset is not 64"},
    {113, FATAL, 0, "section table runs past the end of the file"},
    {114, FATAL, 0, "section table checksum mismatch"},
    {115, WARNING, 0, "minor version newer than this reader (newer optional content skipped)"},
    {116, ERROR, 0, "required feature ZSTD disagrees with the sections' compression"},

    /* ---- 200–299 section table and framing (container helper) ---------------------------- */
    {200, ERROR, 0, "section type is not four printable ASCII characters"},
    {201, ERROR, 0, "section type appears more than once"},
    {202, ERROR, 0, "sections are not in canonical order"},
    {203, ERROR, 0, "unknown section flag bits"},
    {204, ERROR, 0, "unknown compression method"},
    {205, ERROR, 0, "reserved field of a section entry is not zero"},
    {206, ERROR, 0, "section offset differs from the layout rule (alignment, gap or overlap)"},
    {207, ERROR, 0, "section stored_size is zero"},
    {208, ERROR, 0, "section runs past the end of the file"},
    {209, ERROR, 0, "uncompressed section with decoded_size != stored_size"},
    {210, ERROR, 0, "bytes after the end of the last section"},
    {211, ERROR, 0, "non-zero padding byte"},
    {212, ERROR, 0, "unknown section type marked required"},
    {213, WARNING, 0, "unknown optional section skipped"},
    {214, ERROR, 0, "section checksum mismatch"},
    {215, ERROR, 0, "zstd frame header unreadable or without content size"},
    {216, ERROR, 0, "zstd frame content size differs from decoded_size"},
    {217, ERROR, 0, "decoded size exceeds the decoded-bytes cap"},
    {218, ERROR, 0, "zstd decompression failed"},
    {219, ERROR, 0, "stored bytes are not exactly one zstd frame"},
    {220, ERROR, 0, "compressed section with decoded_size 0"},
    {221, WARNING, 0, "a section the present sections depend on is missing"},

    /* ---- 300–349 META (container helper) ------------------------------------------------- */
    {300, ERROR, LBK_SECTION_META, "META shorter than its 16-byte header"},
    {301, ERROR, LBK_SECTION_META, "META reserved field is not zero"},
    {302, ERROR, LBK_SECTION_META, "META size differs from header + entries + string bytes"},
    {303, ERROR, LBK_SECTION_META, "META string offset differs from the packed layout"},
    {304, ERROR, LBK_SECTION_META, "META key is empty, too long or has characters outside [a-z0-9._-]"},
    {305, ERROR, LBK_SECTION_META, "META keys are not strictly ascending (unsorted or duplicate)"},
    {306, ERROR, LBK_SECTION_META, "META value is not valid UTF-8 or contains NUL"},
    {307, WARNING, LBK_SECTION_META, "META lacks the writer key"},
    {308, ERROR, LBK_SECTION_META, "META has no entries"},
    {309, ERROR, LBK_SECTION_META, "META well-known key has a malformed value"},

    /* ---- 350–399 REPT (container helper) ------------------------------------------------- */
    {350, ERROR, LBK_SECTION_REPT, "REPT shorter than its 32-byte header"},
    {351, ERROR, LBK_SECTION_REPT, "REPT size differs from 32 + 32 x record_count"},
    {352, ERROR, LBK_SECTION_REPT, "REPT unknown status"},
    {353, ERROR, LBK_SECTION_REPT, "REPT unknown flag bits or non-zero reserved field"},
    {354, ERROR, LBK_SECTION_REPT, "REPT value is NaN, infinite or negative"},
    {355, ERROR, LBK_SECTION_REPT, "REPT record goes back in time, samples or rays"},
    {356, ERROR, LBK_SECTION_REPT, "REPT elapsed time non-zero although HAS_TIMES is clear"},
    {357, WARNING, LBK_SECTION_REPT, "REPT status disagrees with its limits or last record"},
    {358, ERROR, LBK_SECTION_REPT, "REPT has no records"},

    /* ---- 400–499 OBJS (container helper) ------------------------------------------------- */
    {400, ERROR, LBK_SECTION_OBJS, "OBJS shorter than its 16-byte header"},
    {401, ERROR, LBK_SECTION_OBJS, "OBJS reserved field is not zero"},
    {402, ERROR, LBK_SECTION_OBJS, "OBJS size differs from header + records + name bytes"},
    {403, ERROR, LBK_SECTION_OBJS, "OBJS name offset differs from the packed layout"},
    {404, ERROR, LBK_SECTION_OBJS, "OBJS name is empty, not valid UTF-8 or contains NUL"},
    {405, WARNING, LBK_SECTION_OBJS, "OBJS name is not unique (objects cannot be matched across bakes)"},
    {406, ERROR, LBK_SECTION_OBJS, "OBJS unknown representation"},
    {407, ERROR, LBK_SECTION_OBJS, "OBJS fields unused by the representation are not zero"},
    {408, ERROR, LBK_SECTION_OBJS, "OBJS lightmapped object but the file has no LMAP section"},
    {409, ERROR, LBK_SECTION_OBJS, "OBJS lightmap page index out of range"},
    {410, ERROR, LBK_SECTION_OBJS, "OBJS lightmap rectangle empty or outside its page"},
    {411, ERROR, LBK_SECTION_OBJS, "OBJS object uses an LLG but the file has no LLG section"},
    {412, ERROR, LBK_SECTION_OBJS, "OBJS LLG index out of range"},
    {413, ERROR, LBK_SECTION_OBJS, "OBJS has no objects"},
    {414, ERROR, LBK_SECTION_OBJS, "OBJS lightmap rectangles of two objects overlap"},

    /* ---- 500–599 LMAP (codec helper) ----------------------------------------------------- */

    /* ---- 600–699 GLG (codec helper) ------------------------------------------------------ */

    /* ---- 700–799 LLG (codec helper) ------------------------------------------------------ */

    /* ---- 800–899 DLS (dls helper) -------------------------------------------------------- */

    /* ---- 900–999 DOOR (dls helper) ------------------------------------------------------- */

    /* ---- 1000–1099 OCTP (codec helper) --------------------------------------------------- */
};

const char *lbk_issue_template(uint32_t id, lbk_severity *severity)
{
    for (size_t i = 0; i < sizeof registry / sizeof registry[0]; i++)
        if (registry[i].id == id) {
            if (severity) *severity = registry[i].severity;
            return registry[i].message;
        }
    return NULL;
}

uint32_t lbk_issue_registry_size(void) { return (uint32_t)(sizeof registry / sizeof registry[0]); }

uint32_t lbk_issue_registry_id(uint32_t index) { return index < lbk_issue_registry_size() ? registry[index].id : 0; }

uint32_t lbk_issue_section(uint32_t id)
{
    for (size_t i = 0; i < sizeof registry / sizeof registry[0]; i++)
        if (registry[i].id == id) return registry[i].section;
    return 0;
}
