#!/usr/bin/env python3
"""Writes the seam-stitching worst case for bench/stitch_share.c: a sky-lit room (bench/levels'
shell and window) holding smooth-shaded props — spheres, cylinders, a torus, a rounded column —
whose faces are quads with per-vertex normals of the true surface, so every edge between two
quads is a smooth seam once each quad is its own chart. Twice, as bench/levels writes its levels:

* smooth_props.gltf: no TEXCOORD_1 (lbk makes its own charts, few seams);
* smooth_props_authored.gltf: a Lightmap-Pack-like TEXCOORD_1, one chart per quad
  (bench/levels/geom.lightmap_pack, 1.5 texels between charts): thousands of charts of a few
  texels, every edge a smooth seam — what an artist's "Lightmap Pack" of smooth props gives;

and manifest.json in bench/levels' form (name, gltf, lbk_args). Deterministic: no randomness,
coordinates rounded to 0.1 mm.

    python3 bench/stitch_level.py --out DIR
"""
import argparse
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "levels"))
sys.path.insert(0, os.path.join(HERE, "cycles"))
import families  # noqa: E402
import geom  # noqa: E402
import gltf_write  # noqa: E402

DENSITY = 24.0   # bench/levels' fine density: more texels per chart edge, more seam points


def _r(x):
    return round(x, 4)


def surface(f, nu, nv, wrap_v):
    """Quads of a parametric surface f(u, v) -> (point, normal), u wrapping, v in [0, 1] (closed
    in v too when wrap_v). Each quad: (4 points, 4 normals), counter-clockwise from outside."""
    quads = []
    for j in range(nv):
        for i in range(nu):
            c = [f(((i + di) % nu) / nu, ((j + dj) % nv) / nv if wrap_v else (j + dj) / nv)
                 for di, dj in ((0, 0), (0, 1), (1, 1), (1, 0))]
            c = [(tuple(_r(x) for x in p), n) for p, n in c]
            # a pole quad has two corners at the pole: a triangle
            c = [c[k] for k in range(4) if c[k][0] != c[k - 1][0]]
            pts, nrms = [p for p, _ in c], [n for _, n in c]
            mean = [sum(n[k] for n in nrms) for k in range(3)]
            if geom.dot(geom.poly_normal(pts), mean) < 0:  # counter-clockwise seen from outside
                pts, nrms = pts[::-1], nrms[::-1]
            quads.append((pts, nrms))
    return quads


def sphere(c, r, nu=24, nv=16):
    def f(u, v):
        th, ph = 2 * math.pi * u, math.pi * v
        n = (math.sin(ph) * math.cos(th), -math.cos(ph), math.sin(ph) * math.sin(th))
        return tuple(c[k] + r * n[k] for k in range(3)), n
    # the pole rows are triangles in disguise (two corners at the pole): keep them, the welder
    # drops their zero-length edges
    return surface(f, nu, nv, False)


def cylinder(c, r, h, nu=32, nv=6):
    def f(u, v):
        th = 2 * math.pi * u
        n = (math.cos(th), 0.0, math.sin(th))
        return (c[0] + r * n[0], c[1] + h * v, c[2] + r * n[2]), n
    return surface(f, nu, nv, False)


def torus(c, big, small, nu=40, nv=16):
    def f(u, v):
        th, ph = 2 * math.pi * u, 2 * math.pi * v
        n = (math.cos(ph) * math.cos(th), math.sin(ph), math.cos(ph) * math.sin(th))
        ring = (c[0] + big * math.cos(th), c[1], c[2] + big * math.sin(th))
        return tuple(ring[k] + small * n[k] for k in range(3)), n
    return surface(f, nu, nv, True)


def props():
    """(name, material, quads) of the smooth props, placed on the floor of a 5 x 2.8 x 5 room."""
    out = []
    for k, (x, z, r) in enumerate(((1.0, 1.2, 0.35), (2.4, 1.0, 0.25), (3.8, 1.4, 0.45), (1.4, 3.6, 0.3))):
        out.append(("sphere_%d" % k, "plaster", sphere((x, r + 0.001, z), r)))
    for k, (x, z, r, h) in enumerate(((2.6, 2.6, 0.2, 1.1), (4.2, 3.4, 0.12, 2.0), (0.6, 2.4, 0.3, 0.5))):
        out.append(("column_%d" % k, "oak", cylinder((x, 0.0, z), r, h)))
    out.append(("torus", "plaster", torus((3.0, 0.151, 3.9), 0.5, 0.15)))
    return out


def write(path, authored, room, merged):
    w = gltf_write.Writer()
    mats = {}
    objects = [(n, m, [(p, [geom.poly_normal(p)] * len(p)) for p in polys]) for n, m, polys in room]
    if merged:  # one mesh, as levels exported whole often are: one system for the stitcher
        objects.append(("props", "plaster", [q for _, _, quads in props() for q in quads]))
    else:
        objects += props()
    for name, mat, quads in objects:
        if mat not in mats:
            mats[mat] = w.material(mat, base=families.MATERIALS[mat])
        pos, nrm, idx, uv1 = [], [], [], []
        pack = geom.lightmap_pack([q for q, _ in quads], 1.5 / DENSITY) if authored else None
        for qi, (pts, nrms) in enumerate(quads):
            base = len(pos) // 3
            for vi, (p, n) in enumerate(zip(pts, nrms)):
                pos.extend(_r(x) for x in p)
                nrm.extend(_r(x) for x in n)
                if pack:
                    uv1.extend(_r(x) for x in pack[qi][vi])
            for k in range(1, len(pts) - 1):
                idx.extend((base, base + k, base + k + 1))
        prim = {"pos": pos, "nrm": nrm, "idx": idx, "material": mats[mat]}
        if pack:
            prim["uv1"] = uv1
        w.mesh(name, [prim], extras=None if name != "exterior" else {"lbk_lighting": "none"})
    w.save(path, external_bin=True, scene_extras={"lbk_sky": [1.0, 1.0, 1.0]})


def main():
    ap = argparse.ArgumentParser(description="write the seam-stitching worst-case level")
    ap.add_argument("--out", required=True)
    opt = ap.parse_args()
    os.makedirs(opt.out, exist_ok=True)
    W, H, D = 5.0, 2.8, 5.0
    window = ("front", 0.4, W - 0.4, 0.5, H - 0.3)
    room = list(geom.room_shell(W, H, D, [window]))
    room.append(("exterior", "exterior", geom.hull(W, H, D, [tuple(window) + (0.0,)])))
    scenes = []
    for merged, authored in ((False, False), (False, True), (True, True)):
        stem = "smooth_props" + ("_merged" if merged else "") + ("_authored" if authored else "")
        write(os.path.join(opt.out, stem + ".gltf"), authored, room, merged)
        scenes.append({"name": stem, "gltf": stem + ".gltf", "layout": "authored" if authored else "generated",
                       "lbk_args": ["--sky", "1,1,1", "--texel-density", "%g" % DENSITY]})
    with open(os.path.join(opt.out, "manifest.json"), "w") as f:
        json.dump({"generator": "bench/stitch_level.py", "scenes": scenes}, f, indent=1, sort_keys=True)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
