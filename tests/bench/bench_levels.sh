#!/bin/sh
# The hard-level suite's generator (bench/levels/gen_levels.py, README there):
#   determinism    two runs write the same bytes, and --set dev plus --set validation write
#                  exactly the files of --set all;
#   split          at least 40 levels, each with both layouts, at least 10 in each set;
#   imports        every level (both layouts) bakes in lbk (a minimal bake: 1 bounce, 1
#                  sample pass, no GLG, no denoising, 4 texels/m: import, classification and
#                  the authored layout's checks need no finer, and it halves the time) with
#                  every object of the manifest, and
#                  `lbk inspect` shows the layout it asks for: NAME.gltf all generated charts,
#                  NAME_authored.gltf every lightmapped object on its authored TEXCOORD_1.
# The baker is the release build ($BUILD/lbk; LBK_LEVELS_BAKER overrides): the ASan one would
# take minutes for 88 scenes. cmocka-style lines for tests/run.sh.
set -u
cd "$(dirname "$0")/../.."
. tests/bench/start.shinc
bench_test_start bench_levels determinism split imports
gen=bench/levels/gen_levels.py

# determinism
st=0
python3 $gen --out "$w/a" >"$w/gen_a.log" 2>&1 && python3 $gen --out "$w/b" >"$w/gen_b.log" 2>&1 &&
    python3 $gen --out "$w/d" --set dev >/dev/null 2>&1 && python3 $gen --out "$w/v" --set validation >/dev/null 2>&1 || st=1
if [ $st = 0 ] && diff -r -q "$w/a" "$w/b"; then
    for f in "$w/a"/*.gltf "$w/a"/*.bin; do
        n=$(basename "$f")
        if [ -f "$w/d/$n" ]; then o="$w/d/$n"; elif [ -f "$w/v/$n" ]; then o="$w/v/$n"; else echo "  $n in no set"; st=1; continue; fi
        cmp -s "$f" "$o" || { echo "  $n differs between --set all and its own set"; st=1; }
    done
    [ "$(ls "$w/d" "$w/v" | grep -c -e '\.gltf$' -e '\.bin$')" = "$(ls "$w/a" | grep -c -e '\.gltf$' -e '\.bin$')" ] ||
        { echo "  the sets overlap"; st=1; }
else st=1; fi
if [ $st = 0 ]; then echo "[       OK ] bench_levels_determinism ($(ls "$w/a" | wc -l) files)"; else echo "[  FAILED  ] bench_levels_determinism"; fi
fails=$st

# split: the manifest's levels, layouts and sets (one line per scene: name level layout set objects)
python3 -c '
import json, sys
for s in json.load(open(sys.argv[1]))["scenes"]:
    print(s["name"], s["level"], s["layout"], s["set"], len(s["objects"]))' "$w/a/manifest.json" >"$w/scenes.txt" || fails=1
levels=$(cut -d" " -f2 "$w/scenes.txt" | sort -u | wc -l)
dev=$(awk '$3 == "generated" && $4 == "dev"' "$w/scenes.txt" | wc -l)
val=$(awk '$3 == "generated" && $4 == "validation"' "$w/scenes.txt" | wc -l)
auth=$(awk '$3 == "authored"' "$w/scenes.txt" | wc -l)
if [ "$levels" -ge 40 ] && [ "$dev" -ge 10 ] && [ "$val" -ge 10 ] && [ "$auth" = "$levels" ] && [ $((dev + val)) = "$levels" ]; then
    echo "[       OK ] bench_levels_split ($levels levels: $dev dev, $val validation; $auth authored layouts)"
else echo "[  FAILED  ] bench_levels_split ($levels levels: $dev dev, $val validation; $auth authored)"; fails=1; fi

# imports: bake each scene (two at a time), then compare inspect's OBJS and LMUV lines
st=0
if [ ! -x "$lbk" ]; then echo "  no baker $lbk"; st=1; fi
[ $st = 0 ] && cut -d" " -f1 "$w/scenes.txt" | xargs -P 2 -I{} sh -c '
    "$1" bake "$2/a/$3.gltf" -o "$2/$3.lbk" --samples 1 --max-bounces 1 --target-error none --no-glg \
        --denoise off --threads 1 -q --texel-density 4 >"$2/$3.bake.log" 2>&1 && "$1" inspect "$2/$3.lbk" >"$2/$3.inspect" 2>&1 ||
        echo "  $3: lbk bake/inspect failed: $(tail -n 2 "$2/$3.bake.log")"' _ "$lbk" "$w" {} >"$w/bake_errors.txt"
[ -s "$w/bake_errors.txt" ] && { cat "$w/bake_errors.txt"; st=1; }
n=0
while read -r name level layout lset nobj; do
    [ $st = 0 ] || break
    o=$(sed -n 's/^OBJS .* \([0-9][0-9]*\) objects: \([0-9][0-9]*\) lightmapped.*/\1 \2/p' "$w/$name.inspect")
    u=$(sed -n 's/^LMUV .* objects (\([0-9][0-9]*\) authored, \([0-9][0-9]*\) generated).*/\1 \2/p' "$w/$name.inspect")
    set -- $o $u
    if [ $# != 4 ]; then echo "  $name: no OBJS/LMUV line"; st=1; break; fi
    if [ "$1" != "$nobj" ] || [ "$2" -lt 1 ]; then echo "  $name: $1 objects ($2 lightmapped), the manifest has $nobj"; st=1; fi
    if [ "$layout" = authored ]; then want="$2 0"; else want="0 $2"; fi
    if [ "$3 $4" != "$want" ]; then echo "  $name ($layout): $3 authored, $4 generated of $2 lightmapped"; st=1; fi
    n=$((n + 1))
done <"$w/scenes.txt"
if [ $st = 0 ] && [ "$n" -ge 80 ]; then echo "[       OK ] bench_levels_imports ($n scenes baked)"
else echo "[  FAILED  ] bench_levels_imports"; fails=1; fi
echo "[==========] 3 test(s) run."
[ "$fails" = 0 ] && rm -rf "$w"
exit "$fails"
