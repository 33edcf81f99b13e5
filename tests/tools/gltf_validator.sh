#!/bin/sh
# The Khronos glTF-Validator over `lbk export --gltf` of the five shared scenes
# (scenes/ of the repository, or $LBK_SCENES): each is baked with a small sample budget (BAKE, the release
# binary: speed), exported (LBK, the ASan binary: the exporter is what is tested), and validated
# (tests/tools/gltf_validate.mjs); any validator error fails. Prints one line per file.
# usage: gltf_validator.sh BAKE LBK VALIDATOR_DIR OUTDIR
set -u
BAKE=$1; LBK=$2; VALIDATOR=$3; OUT=$4
S=${LBK_SCENES:-scenes}
rm -rf "$OUT"; mkdir -p "$OUT"
status=0
one() {
  name=$1; scene=$2; shift 2
  if [ ! -r "$S/$scene" ]; then
    echo "$name: missing input $S/$scene (the scenes are in scenes/, or under \$LBK_SCENES when set)"; status=1; return
  fi
  if ! "$BAKE" bake "$S/$scene" -o "$OUT/$name.lbk" --samples 16 --threads 2 -q "$@" >"$OUT/$name.bake.log" 2>&1; then
    echo "$name: bake failed"; tail -n 5 "$OUT/$name.bake.log"; status=1; return
  fi
  if ! "$LBK" export "$OUT/$name.lbk" --gltf "$OUT/$name.glb" --scene "$S/$scene" >"$OUT/$name.export.log" 2>&1; then
    echo "$name: export failed"; tail -n 5 "$OUT/$name.export.log"; status=1; return
  fi
  cat "$OUT/$name.export.log"
}
one cornell cornell_box/CornellBox-Original.gltf --texel-density 16
one bjs cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf
one room room_with_doors/room.glb --sky 1,1,1
one lamp lights_punctual_lamp/LightsPunctualLamp.gltf
one bottle water_bottle_draco/WaterBottle.gltf
node "$(dirname "$0")/gltf_validate.mjs" "$VALIDATOR" "$OUT"/*.glb || status=1
exit $status
