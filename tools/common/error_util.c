#include "tools/common/error_util.h"

#include <stdarg.h>
#include <stdio.h>

int tl_fail(char err[TL_ERR_LEN], int status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, TL_ERR_LEN, fmt, ap);
        va_end(ap);
    }
    return status;
}
