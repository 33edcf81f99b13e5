/* The version of the library linked at run time, as opposed to the headers compiled against. */
#include "lbk/lbk.h"

unsigned lbk_version_number(void) { return LBK_LIBRARY_VERSION_NUMBER; }

const char *lbk_version_string(void) { return LBK_LIBRARY_VERSION_STRING; }
