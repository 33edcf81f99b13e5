#!/bin/sh
# Blender (Debian package `blender`, 3.4) imports every `lbk export --gltf` of the shared scenes
# without errors (bench/blender_import.py); prints the import time and what it found. Not in
# `make test` (Blender is large and optional); SKIPPED when blender is not installed.
# usage: blender_import.sh LBK OUTDIR
set -u
LBK=$1; OUT=$2
S=${LBK_SCENES:-scenes}
if ! command -v blender >/dev/null 2>&1; then
  echo "SKIPPED blender import (blender not installed: apt-get install blender python3-numpy)"; exit 0
fi
if [ ! -d "$S" ]; then echo "SKIPPED blender import (no shared scenes at $S)"; exit 0; fi
rm -rf "$OUT"; mkdir -p "$OUT"
status=0
one() {
  name=$1; scene=$2; shift 2
  if ! "$LBK" bake "$S/$scene" -o "$OUT/$name.lbk" --samples 16 --threads 2 -q "$@" >"$OUT/$name.log" 2>&1 ||
     ! "$LBK" export -q "$OUT/$name.lbk" --gltf "$OUT/$name.glb" --scene "$S/$scene" >>"$OUT/$name.log" 2>&1; then
    echo "blender import: $name: bake or export failed"; tail -n 5 "$OUT/$name.log"; status=1; return
  fi
  blender -b --factory-startup --python "$(dirname "$0")/blender_import.py" -- "$OUT/$name.glb" >"$OUT/$name.blender.log" 2>&1
  rc=$?
  # errors the importer only prints (operator reports) count too
  if [ $rc -ne 0 ] || ! grep -q BLENDER_IMPORT_OK "$OUT/$name.blender.log" || grep -Eq '^(Error|ERROR|Traceback)' "$OUT/$name.blender.log"; then
    echo "blender import: $name: FAILED"; grep -E 'BLENDER_IMPORT|Error|Traceback' "$OUT/$name.blender.log" | head -n 10; status=1
  else
    echo "blender import: $(grep BLENDER_IMPORT_OK "$OUT/$name.blender.log" | sed 's/^BLENDER_IMPORT_OK //')"
  fi
}
echo "Blender $(blender --version 2>/dev/null | head -n 1 | sed 's/^Blender //') importing lbk export --gltf of the shared scenes"
one cornell cornell_box/CornellBox-Original.gltf --texel-density 16
one bjs cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf
one room room_with_doors/room.glb --sky 1,1,1
one lamp lights_punctual_lamp/LightsPunctualLamp.gltf
one bottle water_bottle_draco/WaterBottle.gltf
exit $status
