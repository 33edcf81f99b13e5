/* Validation: every check of spec/validation.md, reported with a stable ID.
 *
 * Thread safety: every function is safe to call from any thread (a run keeps its state in its
 * own call; the callback is called on the caller's thread). */
#ifndef LBK_VALIDATE_H
#define LBK_VALIDATE_H

#include "lbk/container.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum lbk_severity {
    LBK_SEVERITY_WARNING = 0, /* the file is usable; something is unusual */
    LBK_SEVERITY_ERROR = 1,   /* a section is unusable; the file is invalid */
    LBK_SEVERITY_FATAL = 2    /* the file cannot be read at all; later checks were skipped */
} lbk_severity;

/* What the callback gets (frozen). */
typedef struct lbk_issue {
    uint32_t id;           /* stable number from spec/validation.md */
    lbk_severity severity;
    uint32_t section_type; /* 0 for header/table issues */
    uint64_t offset;       /* byte offset in the file (for compressed sections: of the section start) */
    char message[160];     /* English, one line, includes the offending values */
} lbk_issue;

/* Called once per issue, in the order the checks run: header, section table and padding, section
 * checksums in file order, then each section's decode and content checks in dependency order
 * (META, REPT, LMAP, GLG, LLG, OCTP, OBJS, DLS, DOOR; spec/validation.md). Return non-zero to stop. */
typedef int (*lbk_issue_callback)(void *user, const lbk_issue *issue);

/* Size-tagged (lbk.h): set size with LBK_VALIDATE_OPTIONS_INIT; NULL options mean defaults. */
typedef struct lbk_validate_options {
    size_t size;
    const lbk_allocator *allocator; /* NULL: malloc/free */
    uint64_t max_decoded_bytes; /* as lbk_read_options; 0: default */
} lbk_validate_options;
#define LBK_VALIDATE_OPTIONS_INIT LBK_SIZED_INIT(lbk_validate_options)

typedef struct lbk_validate_summary {
    uint32_t fatal, errors, warnings;
} lbk_validate_summary;

/* Runs every check on a byte buffer. Returns LBK_OK when the checks ran (whatever they found);
 * the summary tells whether the file is valid (fatal == 0 && errors == 0). */
LBK_API lbk_result lbk_validate_memory(const void *data, size_t size, const lbk_validate_options *options,
                                       lbk_issue_callback callback, void *user, lbk_validate_summary *summary);
LBK_API lbk_result lbk_validate_file(const char *path, const lbk_validate_options *options,
                                     lbk_issue_callback callback, void *user, lbk_validate_summary *summary);

/* The registry: severity and message template of an ID; NULL if unknown. */
LBK_API const char *lbk_issue_template(uint32_t id, lbk_severity *severity);
/* Enumerates the registry: number of IDs, and the ID at a position (ascending; 0 past the end). */
LBK_API uint32_t lbk_issue_registry_count(void);
LBK_API uint32_t lbk_issue_registry_id(uint32_t index);
/* Section type an ID belongs to (0: header and section table); 0 if unknown. */
LBK_API uint32_t lbk_issue_section(uint32_t id);

#ifdef __cplusplus
}
#endif
#endif
