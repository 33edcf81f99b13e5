#!/bin/sh
# The scale bench's generator (bench/scale/gen_city.py, README there):
#   determinism   two runs of the 1/64 part write the same bytes;
#   parts         a part is a part of the whole: the 1/64 part's buffer is the start of the 1/16
#                 part's (the same buildings first, drawn in the same order), and the whole city
#                 has the size the bench promises (256 buildings, at least 1 M triangles);
#   bakes         the one-building part bakes in lbk (a minimal bake) with both its objects.
# The baker is the release build ($BUILD/lbk; LBK_LEVELS_BAKER overrides). cmocka-style lines.
set -u
cd "$(dirname "$0")/../.."
. tests/bench/start.shinc
bench_test_start bench_scale determinism parts bakes
gen=bench/scale/gen_city.py
fails=0

st=0
python3 $gen --out "$w/a" --fraction 0.015625 >/dev/null && python3 $gen --out "$w/b" --fraction 0.015625 >/dev/null || st=1
[ $st = 0 ] && diff -r -q "$w/a" "$w/b" || st=1
if [ $st = 0 ]; then echo "[       OK ] bench_scale_determinism"; else echo "[  FAILED  ] bench_scale_determinism"; fails=1; fi

st=0
python3 $gen --out "$w/q" --fraction 0.0625 >/dev/null || st=1
whole=$(python3 $gen --out "$w/whole" --stats-only) || st=1
size=$(wc -c <"$w/a/city.bin")
[ $st = 0 ] && cmp -s -n "$size" "$w/a/city.bin" "$w/q/city.bin" || { echo "  the 1/64 part is not the start of the 1/16 part"; st=1; }
set -- $whole
[ "${2:-0}" = 256 ] && [ "${6:-0}" -ge 1000000 ] || { echo "  whole city: $whole"; st=1; }
if [ $st = 0 ]; then echo "[       OK ] bench_scale_parts (whole: $2 buildings, $6 triangles)"; else echo "[  FAILED  ] bench_scale_parts"; fails=1; fi

st=0
python3 $gen --out "$w/one" --fraction 0.00390625 >/dev/null || st=1
[ $st = 0 ] && "$lbk" bake "$w/one/city.gltf" -o "$w/one.lbk" --samples 1 --max-bounces 1 --target-error none --no-glg \
    --denoise off --texel-density 1 --threads 2 >"$w/one.log" 2>&1 || { echo "  the bake failed: $w/one.log"; st=1; }
[ $st = 0 ] && "$lbk" inspect "$w/one.lbk" >"$w/one.txt" 2>&1 || st=1
[ $st = 0 ] && grep -q "2 objects: 2 lightmapped" "$w/one.txt" || { echo "  not both objects lightmapped: $w/one.txt"; st=1; }
if [ $st = 0 ]; then echo "[       OK ] bench_scale_bakes"; else echo "[  FAILED  ] bench_scale_bakes"; fails=1; fi
echo "[==========] 3 test(s) run."
exit $fails
