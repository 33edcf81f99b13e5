#!/bin/sh
# make demo: bake the embedded Cornell box, validate and inspect the container, and write a PNG
# preview of the lightmap atlas. Everything lands in out/demo/.
set -eu
BUILD=${1:-build}
LBK="$BUILD/lbk"
OUT=out/demo
mkdir -p "$OUT"
echo "== lbk bake scenes/cornell_box/CornellBox-Original.gltf (preset fast, 64 texels/m: the box is 2 m across)"
"$LBK" bake scenes/cornell_box/CornellBox-Original.gltf -o "$OUT/cornell_box.lbk" --preset fast --texel-density 64 \
    --json-report "$OUT/cornell_box.report.json"
echo "== lbk validate"
"$LBK" validate "$OUT/cornell_box.lbk"
echo "== lbk inspect"
"$LBK" inspect "$OUT/cornell_box.lbk"
echo "== lbk export --png"
"$LBK" export "$OUT/cornell_box.lbk" --png "$OUT/preview"
echo
echo "demo: container  $OUT/cornell_box.lbk"
echo "      report     $OUT/cornell_box.report.json"
echo "      previews   $(ls "$OUT"/preview/*.png 2>/dev/null | tr '\n' ' ')"
