/* The registry of validation issues: one row per stable ID, mirrored in spec/validation.md.
 *
 * Rules for every editor:
 *   - IDs are stable and never reused; a retired check keeps its row with "(retired)" in the text.
 *   - Rows stay sorted by ID (a test checks this); add rows only inside your own block.
 *   - Severity: FATAL = nothing further can be read; ERROR = the file is invalid;
 *     WARNING = the file is valid but something is unusual.
 *   - `section` is the fourcc the issue belongs to (0 for header and section-table issues).
 *   - The message is the generic text; the issue a validator reports carries the values. */
#include "lbk/error_map.h"
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
    {117, ERROR, 0, "required feature LMAP_BLOCK is set but there is no LMAP section"},

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
    {500, ERROR, LBK_SECTION_LMAP, "LMAP shorter than its 16-byte header"},
    {501, ERROR, LBK_SECTION_LMAP, "LMAP reserved field (or reserved encoding bits) is not zero"},
    {502, ERROR, LBK_SECTION_LMAP, "LMAP page_count is zero or the page table runs past the section"},
    {503, ERROR, LBK_SECTION_LMAP, "LMAP page width or height outside 1..16384"},
    {504, ERROR, LBK_SECTION_LMAP, "LMAP texel_count differs from the sum of page areas"},
    {505, ERROR, LBK_SECTION_LMAP, "LMAP page first_texel differs from the running texel count"},
    {506, ERROR, LBK_SECTION_LMAP, "LMAP plane offset differs from the packed 16-byte-aligned layout"},
    {507, ERROR, LBK_SECTION_LMAP, "LMAP section size differs from the end of the last plane"},
    {508, ERROR, LBK_SECTION_LMAP, "LMAP non-zero padding byte between planes"},
    {509, ERROR, LBK_SECTION_LMAP, "LMAP irradiance texel has an Inf/NaN channel (exponent 31)"},
    {510, WARNING, LBK_SECTION_LMAP, "LMAP highlight direction shorter than 1/2 (decodes as +Z)"},
    {511, ERROR, LBK_SECTION_LMAP, "LMAP scale is not a positive finite power of two"},
    {512, ERROR, LBK_SECTION_LMAP, "LMAP page plane format is not defined"},
    {513, ERROR, LBK_SECTION_LMAP, "LMAP block-encoded page width or height is not a multiple of 4"},
    {514, ERROR, LBK_SECTION_LMAP, "LMAP BC6H block uses a reserved mode"},
    {515, ERROR, LBK_SECTION_LMAP, "LMAP block-encoded pages disagree with the required feature LMAP_BLOCK"},

    /* ---- 600–699 GLG (codec helper) ------------------------------------------------------ */
    {600, ERROR, LBK_SECTION_GLG, "GLG shorter than its 32-byte header"},
    {601, ERROR, LBK_SECTION_GLG, "GLG header reserved bytes are not zero"},
    {602, ERROR, LBK_SECTION_GLG, "GLG has fewer than 4 probes or no tetrahedra"},
    {603, ERROR, LBK_SECTION_GLG, "GLG section size differs from the layout of its counts"},
    {604, ERROR, LBK_SECTION_GLG, "GLG non-zero padding byte"},
    {605, ERROR, LBK_SECTION_GLG, "GLG probe position is NaN or infinite"},
    {606, ERROR, LBK_SECTION_GLG, "GLG tetrahedron vertex index out of range or repeated"},
    {607, ERROR, LBK_SECTION_GLG, "GLG tetrahedron is not positively oriented (volume <= 0)"},
    {608, ERROR, LBK_SECTION_GLG, "GLG neighbour index out of range"},
    {609, ERROR, LBK_SECTION_GLG, "GLG adjacency not symmetric or neighbour does not share the face"},
    {610, WARNING, LBK_SECTION_GLG, "GLG probe belongs to no tetrahedron"},
    {611, ERROR, LBK_SECTION_GLG, "GLG scale is not a positive finite power of two"},

    /* ---- 700–799 LLG (codec helper) ------------------------------------------------------ */
    {700, ERROR, LBK_SECTION_LLG, "LLG shorter than its 32-byte header"},
    {701, ERROR, LBK_SECTION_LLG, "LLG reserved field is not zero"},
    {702, ERROR, LBK_SECTION_LLG, "LLG grid_count is zero or the grid table runs past the section"},
    {703, ERROR, LBK_SECTION_LLG, "LLG section size differs from the layout of its counts"},
    {704, ERROR, LBK_SECTION_LLG, "LLG non-zero padding byte"},
    {705, ERROR, LBK_SECTION_LLG, "LLG box centre, axis or half extent is NaN or infinite"},
    {706, ERROR, LBK_SECTION_LLG, "LLG box axes are not orthonormal"},
    {707, ERROR, LBK_SECTION_LLG, "LLG box half extent is not positive"},
    {708, ERROR, LBK_SECTION_LLG, "LLG lattice dimension outside 2..64"},
    {709, ERROR, LBK_SECTION_LLG, "LLG grid probe_offset differs from the running probe count"},
    {710, ERROR, LBK_SECTION_LLG, "LLG grid vertex_offset differs from the running vertex count"},
    {711, ERROR, LBK_SECTION_LLG, "LLG header probe or vertex count differs from the grids"},
    {712, ERROR, LBK_SECTION_LLG, "LLG vertex visibility reserved byte is not zero"},
    {713, ERROR, LBK_SECTION_LLG, "LLG scale is not a positive finite power of two"},

    /* ---- 800–899 DLS (dls helper) -------------------------------------------------------- */
    {800, ERROR, LBK_SECTION_DLS, "DLS shorter than its 96-byte header"},
    {801, ERROR, LBK_SECTION_DLS, "DLS size differs from the layout its header counts imply"},
    {802, ERROR, LBK_SECTION_DLS, "DLS padding byte is not zero"},
    {803, ERROR, LBK_SECTION_DLS, "DLS target space size disagrees with the LMAP, GLG or LLG section (or that section is missing)"},
    {804, ERROR, LBK_SECTION_DLS, "DLS target space size exceeds 2^32"},
    {805, ERROR, LBK_SECTION_DLS, "DLS array count in the header differs from what the sets and clusters use"},
    {810, ERROR, LBK_SECTION_DLS, "DLS set name is empty, outside the string blob, not valid UTF-8 or contains NUL"},
    {811, ERROR, LBK_SECTION_DLS, "DLS set name appears twice"},
    {812, ERROR, LBK_SECTION_DLS, "DLS set kind is unknown"},
    {813, ERROR, LBK_SECTION_DLS, "DLS set light or member range differs from the packed layout"},
    {814, ERROR, LBK_SECTION_DLS, "DLS light name is empty, outside the string blob, not valid UTF-8 or contains NUL"},
    {815, ERROR, LBK_SECTION_DLS, "DLS combination members invalid (fewer than 2, out of range, not ascending, itself, a combination) or members on a non-combination set"},
    {816, ERROR, LBK_SECTION_DLS, "DLS set reserved field is not zero"},
    {820, ERROR, LBK_SECTION_DLS, "DLS cluster form is unknown"},
    {821, ERROR, LBK_SECTION_DLS, "DLS cluster target space is unknown"},
    {822, ERROR, LBK_SECTION_DLS, "DLS clusters are not ordered by (space, form)"},
    {823, ERROR, LBK_SECTION_DLS, "DLS cluster first index differs from the packed layout, or a field its form does not use is not zero"},
    {824, ERROR, LBK_SECTION_DLS, "DLS cluster set list: count outside the form's range, set out of range or not strictly ascending"},
    {825, ERROR, LBK_SECTION_DLS, "DLS cluster overlaps field disagrees with its form and set list"},
    {826, ERROR, LBK_SECTION_DLS, "DLS run is empty, past the end of its target space, or runs are not ascending and merged"},
    {827, ERROR, LBK_SECTION_DLS, "DLS cluster target count is zero or differs from the sum of its run lengths"},
    {828, ERROR, LBK_SECTION_DLS, "DLS cluster entry count disagrees with its targets or exceeds the form's cap"},
    {829, ERROR, LBK_SECTION_DLS, "DLS target belongs to more than one cluster"},
    {830, ERROR, LBK_SECTION_DLS, "DLS packed sub-groups: chain of runs or targets broken, none, or more than 128 targets"},
    {831, ERROR, LBK_SECTION_DLS, "DLS packed sub-group slot out of range, not ascending, or an unused slot is not zero"},
    {832, WARNING, LBK_SECTION_DLS, "DLS cluster lists a set that none of its targets uses"},
    {840, ERROR, LBK_SECTION_DLS, "DLS prefix word count differs from what the target count needs"},
    {841, ERROR, LBK_SECTION_DLS, "DLS prefix bits past the last field of a word are not zero"},
    {842, ERROR, LBK_SECTION_DLS, "DLS prefix base differs from the sum of the counts before it"},
    {843, ERROR, LBK_SECTION_DLS, "DLS prefix counts do not sum to the cluster's entry count"},
    {844, ERROR, LBK_SECTION_DLS, "DLS entry slot is outside the cluster's set list"},
    {845, ERROR, LBK_SECTION_DLS, "DLS entry slots of a target are not strictly ascending"},
    {850, ERROR, LBK_SECTION_DLS, "DLS texel entry has an Inf/NaN R11G11B10F channel"},

    /* ---- 900–999 DOOR (dls helper) ------------------------------------------------------- */
    {900, ERROR, LBK_SECTION_DOOR, "DOOR shorter than its 32-byte header"},
    {901, ERROR, LBK_SECTION_DOOR, "DOOR size differs from the layout its header counts imply"},
    {902, ERROR, LBK_SECTION_DOOR, "DOOR reserved field or padding byte is not zero"},
    {903, ERROR, LBK_SECTION_DOOR, "DOOR is present but there is no DLS section"},
    {910, ERROR, LBK_SECTION_DOOR, "DOOR name is empty, outside the string blob, not valid UTF-8 or contains NUL"},
    {911, ERROR, LBK_SECTION_DOOR, "DOOR name appears twice"},
    {912, ERROR, LBK_SECTION_DOOR, "DOOR OBB is not finite, has a negative half extent or non-orthonormal axes"},
    {913, ERROR, LBK_SECTION_DOOR, "DOOR open set is not a DLS set of kind door-open"},
    {914, ERROR, LBK_SECTION_DOOR, "DOOR closed set is neither 0xFFFFFFFF nor a DLS set of kind door-closed"},
    {915, ERROR, LBK_SECTION_DOOR, "DOOR a DLS set belongs to more than one door (or twice to one)"},
    {920, ERROR, LBK_SECTION_DOOR, "DOOR state door range differs from the packed layout or is empty"},
    {921, ERROR, LBK_SECTION_DOOR, "DOOR state door index out of range or not strictly ascending"},
    {922, ERROR, LBK_SECTION_DOOR, "DOOR state set is not a DLS combination set"},
    {923, ERROR, LBK_SECTION_DOOR, "DOOR state lists a door whose open set is not a member of the state's combination set"},
    {924, ERROR, LBK_SECTION_DOOR, "DOOR two states share a combination set"},
    {925, WARNING, LBK_SECTION_DOOR, "DOOR a door-open or door-closed DLS set is named by no door"},
    {926, ERROR, LBK_SECTION_DOOR, "DOOR has no elements"},

    /* ---- 1000–1099 OCTP (codec helper) --------------------------------------------------- */
    {1000, ERROR, LBK_SECTION_OCTP, "OCTP shorter than its 16-byte header"},
    {1001, ERROR, LBK_SECTION_OCTP, "OCTP header reserved bytes are not zero"},
    {1002, ERROR, LBK_SECTION_OCTP, "OCTP has no probes"},
    {1003, ERROR, LBK_SECTION_OCTP, "OCTP section size differs from 16 + 48 x level_count + 1024 x probe_count"},
    {1004, ERROR, LBK_SECTION_OCTP, "OCTP irradiance texel has an Inf/NaN channel (exponent 31)"},
    {1005, ERROR, LBK_SECTION_OCTP, "OCTP depth moment is NaN, infinite or negative"},
    {1006, ERROR, LBK_SECTION_OCTP, "OCTP border texel differs from the interior texel it copies"},
    {1007, ERROR, LBK_SECTION_OCTP, "OCTP probe position is NaN or infinite"},
    {1008, ERROR, LBK_SECTION_OCTP, "OCTP probe reserved bytes are not zero"},
    {1009, ERROR, LBK_SECTION_OCTP, "OCTP scale is not a positive finite power of two"},
    {1010, ERROR, LBK_SECTION_OCTP, "OCTP has more than 3 levels"},
    {1011, ERROR, LBK_SECTION_OCTP, "OCTP level origin, spacing, dims or miss distance invalid"},
    {1012, ERROR, LBK_SECTION_OCTP, "OCTP probe_count or a level's first_probe differs from what the levels imply"},
    {1013, ERROR, LBK_SECTION_OCTP, "OCTP probe offset exceeds half a spacing or position is not grid point + offset"},
    {1014, ERROR, LBK_SECTION_OCTP, "OCTP probe state unknown or statistics out of range"},
    {1015, ERROR, LBK_SECTION_OCTP, "OCTP depth mean exceeds the miss distance or m2 < m1 squared"},

    /* ---- 1100–1199 LMUV (format 1.1) ----------------------------------------------------- */
    {1100, ERROR, LBK_SECTION_LMUV, "LMUV shorter than its 32-byte header"},
    {1101, ERROR, LBK_SECTION_LMUV, "LMUV reserved field or padding byte is not zero"},
    {1102, ERROR, LBK_SECTION_LMUV, "LMUV has no records"},
    {1103, ERROR, LBK_SECTION_LMUV, "LMUV size differs from the layout its header counts imply"},
    {1104, ERROR, LBK_SECTION_LMUV, "LMUV header primitive, vertex or index count differs from what the records use"},
    {1105, ERROR, LBK_SECTION_LMUV, "LMUV record object out of range or records not strictly ascending by object"},
    {1106, ERROR, LBK_SECTION_LMUV, "LMUV record names an object that is not lightmapped"},
    {1107, ERROR, LBK_SECTION_LMUV, "LMUV record kind is unknown"},
    {1108, ERROR, LBK_SECTION_LMUV, "LMUV fields unused by the record's kind are not zero"},
    {1109, ERROR, LBK_SECTION_LMUV, "LMUV authored scale not positive and finite, or offset or uv box not finite or inverted"},
    {1110, ERROR, LBK_SECTION_LMUV, "LMUV authored TEXCOORD_1 box maps outside the object's rectangle"},
    {1111, ERROR, LBK_SECTION_LMUV, "LMUV two records come from the same glTF node"},
    {1112, ERROR, LBK_SECTION_LMUV, "LMUV primitive, vertex or index range differs from the packed layout"},
    {1113, ERROR, LBK_SECTION_LMUV, "LMUV primitive empty, index count not a multiple of 3, or source primitives not ascending"},
    {1114, ERROR, LBK_SECTION_LMUV, "LMUV index out of range of its primitive's vertices"},
    {1115, ERROR, LBK_SECTION_LMUV, "LMUV remap entry out of range of the source primitive's vertices"},
    {1116, ERROR, LBK_SECTION_LMUV, "LMUV lightmap coordinate not finite or outside the object's rectangle"},
    {1117, WARNING, LBK_SECTION_LMUV, "LMUV vertex used by no triangle"},
    {1118, WARNING, LBK_SECTION_LMUV, "LMUV lightmapped object has no record (an engine cannot map it)"},
    {1119, ERROR, LBK_SECTION_LMUV, "LMUV is present but there is no OBJS section"},

    /* ---- 1200–1299 TERR (format 1.4) ----------------------------------------------------- */
    {1200, ERROR, LBK_SECTION_TERR, "TERR shorter than its 16-byte header"},
    {1201, ERROR, LBK_SECTION_TERR, "TERR encoding is not defined"},
    {1202, ERROR, LBK_SECTION_TERR, "TERR unknown flag bits"},
    {1203, ERROR, LBK_SECTION_TERR, "TERR texel_count is 0 or the size differs from 16 + texel_count"},
    {1204, ERROR, LBK_SECTION_TERR, "TERR is present but there is no LMAP section"},
    {1205, ERROR, LBK_SECTION_TERR, "TERR texel_count differs from LMAP's texel_count"},
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

uint32_t lbk_issue_registry_count(void) { return (uint32_t)(sizeof registry / sizeof registry[0]); }

uint32_t lbk_issue_registry_id(uint32_t index) { return index < lbk_issue_registry_count() ? registry[index].id : 0; }

uint32_t lbk_issue_section(uint32_t id)
{
    for (size_t i = 0; i < sizeof registry / sizeof registry[0]; i++)
        if (registry[i].id == id) return registry[i].section;
    return 0;
}
