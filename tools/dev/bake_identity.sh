#!/bin/sh
# Byte-identity check for refactors: bakes every bench scene with two lbk binaries and compares
# the containers byte for byte (and the JSON reports less their timings).
#   tools/dev/bake_identity.sh OLD_LBK NEW_LBK [SCENES_DIR]
# A refactor that claims "same output" runs this before it lands; exit 1 names the first case
# that differs. Cases cover the base transport, light sets/doors, punctual lights with light
# culling, glossy VPLs, octahedral probes, the error map and denoising.
set -eu
old=$1; new=$2
scenes=${3:-${LBK_SCENES:-scenes}}
repo=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0; n=0
run_case() { # name scene args...
    name=$1; scene=$2; shift 2
    if [ ! -f "$scene" ]; then echo "bake_identity: $name: missing scene $scene" >&2; fail=1; return; fi
    "$old" bake "$scene" -o "$tmp/$name.old.lbk" -q --threads 2 "$@" || { echo "bake_identity: $name: old lbk failed" >&2; fail=1; return; }
    "$new" bake "$scene" -o "$tmp/$name.new.lbk" -q --threads 2 "$@" || { echo "bake_identity: $name: new lbk failed" >&2; fail=1; return; }
    n=$((n + 1))
    if cmp -s "$tmp/$name.old.lbk" "$tmp/$name.new.lbk"; then
        echo "same  $name ($(wc -c < "$tmp/$name.new.lbk") bytes)"
    else
        echo "DIFF  $name"; fail=1
    fi
}
run_case cornell        "$repo/scenes/cornell_box/CornellBox-Original.gltf" --samples 128
run_case cornell_extras "$repo/scenes/cornell_box/CornellBox-Original.gltf" --samples 64 --octahedral --glg-lighting --error-map --denoise on --seed 7
run_case leak_rooms     "$repo/scenes/leak_rooms/leak_rooms.gltf" --samples 64
run_case bjs            "$scenes/cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf" --samples 64
run_case room_doors     "$scenes/room_with_doors/room.glb" --samples 32 --sky 1,1,1
run_case lamp           "$scenes/lights_punctual_lamp/LightsPunctualLamp.gltf" --samples 32 --light-culling on --glossy-vpl on
run_case bottle         "$scenes/water_bottle_draco/WaterBottle.gltf" --samples 32
echo "bake_identity: $n cases, $( [ $fail = 0 ] && echo all identical || echo DIFFERENCES )"
exit $fail
