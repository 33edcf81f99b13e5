#!/bin/sh
# The fuzz seeds track the formats (tests/fuzz/README.md): every committed part seed
# (tests/fuzz/corpus_part/*.lbkpart) carries the part format version the baker writes
# (BK_PART_VERSION, bake/dist/dist.h; the version is the u32 at offset 8, spec/part.md §1), and
# every container seed (tests/fuzz/corpus/*.lbk) the container's major version with a minor
# version no newer than the writer's (LBK_FORMAT_VERSION_*, lbk.h; u16s at offsets 8 and 10,
# spec/container.md §2). A seed of an older format is refused before the code under test
# (the part harness does not repair the version), so its runs exercise almost nothing:
# regenerate them with `make fuzz-corpus`. cmocka-style lines for tests/run.sh.
set -u
cd "$(dirname "$0")/../.."
def() { sed -n "s/^#define $1  *\([0-9][0-9]*\).*/\1/p" "$2"; }
part=$(def BK_PART_VERSION bake/dist/dist.h)
major=$(def LBK_FORMAT_VERSION_MAJOR libformat/include/lbk/lbk.h)
minor=$(def LBK_FORMAT_VERSION_MINOR libformat/include/lbk/lbk.h)
u32() { od -A n -t u4 -j "$2" -N 4 "$1" | tr -d ' '; } # little-endian hosts (x86-64, arm64)
u16() { od -A n -t u2 -j "$2" -N 2 "$1" | tr -d ' '; }
bad=0 n=0
for f in tests/fuzz/corpus_part/*.lbkpart; do
    [ -f "$f" ] || continue; n=$((n + 1))
    if [ "$(head -c 7 "$f")" != "LBKPART" ]; then echo "  $f: not a part file"; bad=1; continue; fi
    v=$(u32 "$f" 8)
    if [ "$v" = "$part" ]; then echo "  $f: part format $v"
    else echo "  STALE $f: part format $v, the baker writes $part (make fuzz-corpus)"; bad=1; fi
done
for f in tests/fuzz/corpus/*.lbk; do
    [ -f "$f" ] || continue; n=$((n + 1))
    if [ "$(head -c 4 "$f" | tail -c 3)" != "LBK" ]; then echo "  $f: not a container"; bad=1; continue; fi
    ma=$(u16 "$f" 8) mi=$(u16 "$f" 10)
    if [ "$ma" = "$major" ] && [ "$mi" -le "$minor" ]; then echo "  $f: container format $ma.$mi"
    else echo "  STALE $f: container format $ma.$mi, the writer writes $major.(0..$minor) (make fuzz-corpus)"; bad=1; fi
done
echo "[==========] Running 1 test(s)."
if [ "$bad" = 0 ] && [ "$n" -gt 0 ] && [ -n "$part" ] && [ -n "$major" ] && [ -n "$minor" ]; then
    echo "[       OK ] fuzz_seeds ($n seeds)"; st=0
else echo "[  FAILED  ] fuzz_seeds"; st=1; fi
echo "[==========] 1 test(s) run."
exit $st
