#!/usr/bin/env python3
"""Writes the hard-level suite (README.md): every level of bench/levels/families.py as glTF
2.0 with an external buffer, twice: NAME.gltf (no TEXCOORD_1: lbk generates its charts) and
NAME_authored.gltf (a Lightmap-Pack-like TEXCOORD_1, one chart per face), plus manifest.json.

    python3 bench/levels/gen_levels.py --out DIR [--set dev|validation|all] [--seed-base N]
                                       [--only LEVEL,LEVEL,...]

Deterministic: the same invocation writes the same bytes. Level v of family f is seeded with
seed_base + 100 * f + v; its set is "validation" when v % 3 == 2, otherwise "dev".
"""
import argparse
import json
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "cycles"))
import families  # noqa: E402
import geom  # noqa: E402
import gltf_write  # noqa: E402

LAYOUTS = ("generated", "authored")


# Cycles reference samples (bench/cycles/run.py: per footprint point half of ref_spp; LBK_BENCH_QUICK
# uses ref_spp_quick): at 64 spp per point a sky-lit room's reference has 5-12 % noise per texel,
# more than lbk's error, so every object came out "n/r" (measured 2026-12-06 on table_slab_00);
# noise falls as 1/sqrt(spp). Fine density has 9x the texels (and sensors), so a quarter of the
# samples: about 1.4 % reference noise per texel, as the quick setting at coarse density.
def cycles_spp(density):
    return {"ref_spp": 8192 if density == "coarse" else 2048, "ref_spp_quick": 2048, "calib": [4, 16]}


def all_levels(seed_base):
    """(name, family, variant, seed, set, params) of every level, in a fixed order."""
    out = []
    for fi, (fam, _, variants) in enumerate(families.FAMILIES):
        for v, p in enumerate(variants):
            out.append(("%s_%02d" % (fam, v), fam, v, seed_base + 100 * fi + v, families.level_set(v), p))
    return out


def _r(x):
    """Coordinates rounded to 0.1 mm so no platform's last-bit arithmetic reaches the file."""
    return round(x, 4)


def write_level(lv, path, layout, density):
    """One glTF of the level; authored: TEXCOORD_1 from geom.lightmap_pack (1.5 texels margin)."""
    w = gltf_write.Writer()
    mats = {}
    for name, mat, polys in lv.objects:
        if mat not in mats:
            mats[mat] = w.material(mat, base=families.MATERIALS[mat])
        pos, nrm, idx, corner = geom.triangulate(polys)
        prim = {"pos": [_r(x) for x in pos], "nrm": [_r(x) for x in nrm], "idx": idx, "material": mats[mat]}
        if layout == "authored":
            uv = geom.lightmap_pack(polys, 1.5 / density)
            prim["uv1"] = [_r(c) for pi, vi in corner for c in uv[pi][vi]]
        w.mesh(name, [prim], extras=lv.extras.get(name))
    for name, kind, intensity, at, rot in lv.lights:
        w.light(name, kind, intensity, translation=[_r(x) for x in at] if at else None,
                rotation=[_r(x) for x in rot] if rot else None)
    extras = {"lbk_sky": list(lv.sky)} if max(lv.sky) > 0 else None
    w.save(path, external_bin=True, scene_extras=extras)


def main():
    ap = argparse.ArgumentParser(description="write the hard-level suite")
    ap.add_argument("--out", required=True)
    ap.add_argument("--set", default="all", choices=("dev", "validation", "all"))
    ap.add_argument("--seed-base", type=int, default=1000)
    ap.add_argument("--only", default="", help="comma-separated level names")
    opt = ap.parse_args()
    only = [x for x in opt.only.split(",") if x]
    os.makedirs(opt.out, exist_ok=True)
    known = {lv[0] for lv in all_levels(opt.seed_base)}
    for name in only:
        if name not in known:
            sys.exit("gen_levels: no level %s" % name)
    scenes = []
    for name, fam, v, seed, lset, p in all_levels(opt.seed_base):
        if (opt.set != "all" and lset != opt.set) or (only and name not in only):
            continue
        builder = dict((f, b) for f, b, _ in families.FAMILIES)[fam]
        lv = builder(p, random.Random(seed))
        density = families.DENSITY[p["density"]]
        for layout in LAYOUTS:
            stem = name if layout == "generated" else name + "_authored"
            write_level(lv, os.path.join(opt.out, stem + ".gltf"), layout, density)
            scenes.append({"name": stem, "level": name, "family": fam, "variant": v, "seed": seed, "set": lset,
                           "lighting": lv.lighting, "density": p["density"], "texel_density": density,
                           "layout": layout, "gltf": stem + ".gltf", "sky": list(lv.sky),
                           "lbk_args": ["--sky", ",".join("%g" % x for x in lv.sky), "--texel-density", "%g" % density],
                           "params": p, "objects": [o[0] for o in lv.objects], "thin_m": lv.thin, "cycles": cycles_spp(p["density"])})
    with open(os.path.join(opt.out, "manifest.json"), "w") as f:
        json.dump({"generator": "bench/levels/gen_levels.py", "seed_base": opt.seed_base, "set": opt.set,
                   "scenes": scenes}, f, indent=1, sort_keys=True)
        f.write("\n")
    print("gen_levels: %d scenes (%d levels x %d layouts, set %s) in %s" % (
        len(scenes), len(scenes) // len(LAYOUTS), len(LAYOUTS), opt.set, opt.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
