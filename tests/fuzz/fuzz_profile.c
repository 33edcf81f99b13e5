/* libFuzzer harness for the pack profile parser (tools/convert/profile.c): any text is parsed;
 * a profile that parses must answer every section type's rule without reading out of bounds.
 * A crash or sanitizer report is a finding; a parse error is an answer. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "tools/convert/profile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tl_profile p;
    memset(&p, 0, sizeof p);
    char err[TL_ERR_LEN];
    if (tl_profile_parse((const char *)data, size, "fuzz", &p, err) == 0) {
        static const char types[][5] = {"META", "REPT", "OBJS", "LMAP", "GLG ", "LLG ", "DLS ", "DOOR", "OCTP", "LMUV", "XTRA"};
        for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
            uint32_t t = (uint32_t)types[i][0] | (uint32_t)types[i][1] << 8 | (uint32_t)types[i][2] << 16 |
                         (uint32_t)types[i][3] << 24;
            (void)tl_profile_rule(&p, t);
        }
    }
    return 0;
}
