#!/bin/sh
# The version numbers agree everywhere they are stated: the container format in lbk.h and in the
# spec's title, liblbk's and liblbkbake's versions in their headers, in `lbk --version` and in the
# pkg-config files the build writes from them. cmocka-style lines for tests/run.sh.
set -u
cd "$(dirname "$0")/../.."
: "${BUILD:=build}"
def() { sed -n "s/^#define $1  *\([0-9][0-9]*\).*/\1/p" "$2"; }
fmt="$(def LBK_FORMAT_VERSION_MAJOR libformat/include/lbk/lbk.h).$(def LBK_FORMAT_VERSION_MINOR libformat/include/lbk/lbk.h)"
lib="$(def LBK_LIBRARY_VERSION_MAJOR libformat/include/lbk/lbk.h).$(def LBK_LIBRARY_VERSION_MINOR libformat/include/lbk/lbk.h).$(def LBK_LIBRARY_VERSION_PATCH libformat/include/lbk/lbk.h)"
bake="$(def LBK_BAKE_LIBRARY_VERSION_MAJOR bake/include/lbk/bake.h).$(def LBK_BAKE_LIBRARY_VERSION_MINOR bake/include/lbk/bake.h).$(def LBK_BAKE_LIBRARY_VERSION_PATCH bake/include/lbk/bake.h)"
bad=0
check() { # what got want
    if [ "$2" = "$3" ]; then echo "  $1: $2"; else echo "  MISMATCH $1: '$2', expected '$3'"; bad=1; fi
}
check "spec/container.md title" "$(sed -n '1s/.*format version \([0-9.]*\).*/\1/p' spec/container.md)" "$fmt"
v=$("$BUILD/lbk" --version 2>&1)
check "lbk --version" "$v" "lbk $lib (liblbk $lib, liblbkbake $bake, container format $fmt)"
[ -f "$BUILD/lbk.pc" ] && check "lbk.pc" "$(sed -n 's/^Version: //p' "$BUILD/lbk.pc")" "$lib"
[ -f "$BUILD/lbk-bake.pc" ] && check "lbk-bake.pc" "$(sed -n 's/^Version: //p' "$BUILD/lbk-bake.pc")" "$bake"
echo "[==========] Running 1 test(s)."
if [ "$bad" = 0 ] && [ -n "$fmt" ] && [ "$lib" != ".." ]; then echo "[       OK ] versions"; st=0
else echo "[  FAILED  ] versions"; st=1; fi
echo "[==========] 1 test(s) run."
exit $st
