/* Names and descriptions of lbk_result codes, and printable four-character codes. */
#include "xxh.h"

#include "internal.h"

static const struct {
    const char *name;
    const char *message;
} result_text[LBK_RESULT_COUNT_] = {
    [LBK_OK] = {"LBK_OK", "success"},
    [LBK_ERR_INVALID_ARGUMENT] = {"LBK_ERR_INVALID_ARGUMENT", "invalid argument"},
    [LBK_ERR_OUT_OF_MEMORY] = {"LBK_ERR_OUT_OF_MEMORY", "out of memory"},
    [LBK_ERR_IO] = {"LBK_ERR_IO", "input/output error (see errno)"},
    [LBK_ERR_NOT_LBK] = {"LBK_ERR_NOT_LBK", "not an lbk container (magic mismatch or text-mode damage)"},
    [LBK_ERR_TRUNCATED] = {"LBK_ERR_TRUNCATED", "the data ends before the structure it describes"},
    [LBK_ERR_UNSUPPORTED_VERSION] = {"LBK_ERR_UNSUPPORTED_VERSION", "unsupported container major version"},
    [LBK_ERR_UNSUPPORTED_FEATURE] = {"LBK_ERR_UNSUPPORTED_FEATURE",
                                     "unknown required feature flag or required section type, or an "
                                     "options/desc field this library does not know"},
    [LBK_ERR_CORRUPT] = {"LBK_ERR_CORRUPT", "the container breaks a structural rule of the format"},
    [LBK_ERR_CHECKSUM] = {"LBK_ERR_CHECKSUM", "checksum mismatch"},
    [LBK_ERR_DECOMPRESS] = {"LBK_ERR_DECOMPRESS", "decompression failed or gave the wrong length"},
    [LBK_ERR_NOT_FOUND] = {"LBK_ERR_NOT_FOUND", "not found"},
    [LBK_ERR_LIMIT] = {"LBK_ERR_LIMIT", "a size exceeds a limit"},
    [LBK_ERR_RANGE] = {"LBK_ERR_RANGE", "a value is outside the range the encoding can hold"},
    [LBK_ERR_OVERLAPS] = {"LBK_ERR_OVERLAPS", "more dynamic light set overlaps than the format allows"},
    [LBK_ERR_CANCELLED] = {"LBK_ERR_CANCELLED", "cancelled by the caller"},
    [LBK_ERR_BAD_INPUT] = {"LBK_ERR_BAD_INPUT", "the input is unusable"},
    [LBK_ERR_INTERNAL] = {"LBK_ERR_INTERNAL", "internal error"},
    [LBK_ERR_MISMATCH] = {"LBK_ERR_MISMATCH", "the container does not describe the caller's data"},
};

const char *lbk_result_name(lbk_result r)
{
    if ((unsigned)r < LBK_RESULT_COUNT_ && result_text[r].name) return result_text[r].name;
    return "LBK_ERR_UNKNOWN";
}

const char *lbk_result_message(lbk_result r)
{
    if ((unsigned)r < LBK_RESULT_COUNT_ && result_text[r].message) return result_text[r].message;
    return "unknown result code";
}

void lbk_fourcc_string(uint32_t type, char out[5])
{
    for (int i = 0; i < 4; i++) {
        unsigned c = (type >> (8 * i)) & 0xffu;
        out[i] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
    }
    out[4] = '\0';
}

uint64_t lbk_hash64(const void *data, size_t size) { return XXH3_64bits(data, size); }
