#!/usr/bin/env python3
"""Writes the scale bench's level (bench/scale/README.md): a city of blocks on a street grid, each
block one building with interiors — floors of rooms behind windowed facades, partition walls
with doorways — on a sidewalk beside asphalt streets, lit by a sky and the sun. Plain Python 3,
seeded, deterministic: the same invocation writes the same bytes.

    python3 bench/scale/gen_city.py --out DIR [--fraction F] [--seed N] [--blocks N] [--stats-only]

--fraction F writes the first F of the N x N blocks at the same density, in square shells from
one corner (1/16 of 16 x 16 is a 4 x 4 district), so a fraction's texels, triangles and probes
are about that fraction of the whole (the bench's growth study). Every building is drawn from
the seed in the same order whatever the fraction, so a fraction is a part of the whole city. The
whole default city (16 x 16 blocks) has about 1.05 M triangles and, at 3.6 texels per metre,
about 50 M texels.
"""
import argparse
import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "levels"))
sys.path.insert(0, os.path.join(HERE, "..", "cycles"))
import geom  # noqa: E402
import gltf_write  # noqa: E402

PITCH = 34.0          # block pitch, metres: the lot and half a street on each side
STREET = 8.0          # street width between two sidewalks
WALK = 2.5            # sidewalk width around a lot
FLOOR_H, ROOM_H = 3.3, 3.0  # storey pitch and room height (the slab between: 0.3 m)
WALL_T = 0.3          # facade thickness (the room's wall planes to the outside)
SUN_DIR = geom.norm((0.35, -0.7, -0.55))
MATERIALS = {"facade": (0.55, 0.5, 0.45), "plaster": (0.8, 0.78, 0.75), "floor": (0.42, 0.32, 0.22),
             "roof": (0.3, 0.3, 0.32), "asphalt": (0.12, 0.12, 0.12), "sidewalk": (0.45, 0.45, 0.43)}


def _move(polys, dx, dy, dz):
    return [[(x + dx, y + dy, z + dz) for x, y, z in p] for p in polys]


def _windows(rng, length, floors):
    """Window spans (a0, a1) along a facade of `length` metres: one per ~3.2 m, 1.4 m wide."""
    n = max(1, int(length / 3.2))
    step = length / n
    return [(round(step * (k + 0.5) - 0.7, 2), round(step * (k + 0.5) + 0.7, 2)) for k in range(n)]


def _partitions(rng, W, D):
    """Interior walls of boxes (12 cm) with a doorway each: one across x, one across z on
    wider floors. Returns boxes (lo, hi, faces to skip)."""
    t, door_w, door_h = 0.12, 1.0, 2.1
    out = []
    z0 = round(D / 2 + rng.randint(-100, 100) / 100.0, 2)
    dx = round(1.0 + rng.random() * (W - 3.0), 2)
    out += [((0.0, 0.0, z0), (dx, ROOM_H, z0 + t), ("bottom", "top")),
            ((dx + door_w, 0.0, z0), (W, ROOM_H, z0 + t), ("bottom", "top")),
            ((dx, door_h, z0), (dx + door_w, ROOM_H, z0 + t), ("top",))]
    if W > 16:
        x0 = round(W / 2 + rng.randint(-100, 100) / 100.0, 2)
        dz = round(0.5 + rng.random() * (z0 - 2.0), 2)
        out += [((x0, 0.0, 0.0), (x0 + t, ROOM_H, dz), ("bottom", "top")),
                ((x0, 0.0, dz + door_w), (x0 + t, ROOM_H, z0), ("bottom", "top")),
                ((x0, door_h, dz), (x0 + t, ROOM_H, dz + door_w), ("top",))]
    return out


def building(rng):
    """(W, D, floors, polygons by material) of one building in its own frame: the rooms' planes
    x = 0..W, z = 0..D, the ground at y = 0, the facade WALL_T outside the planes."""
    W = round(14.0 + rng.random() * 10.0, 2)
    D = round(14.0 + rng.random() * 10.0, 2)
    floors = rng.randint(3, 12)
    polys = {"facade": [], "plaster": [], "floor": [], "roof": []}
    win_x, win_z = _windows(rng, W, floors), _windows(rng, D, floors)
    hull_open = []
    for f in range(floors):
        y0 = WALL_T + f * FLOOR_H
        wy = (0.9, 2.3)
        openings = [(w, a0, a1) + wy for w in ("back", "front") for a0, a1 in win_x]
        openings += [(w, a0, a1) + wy for w in ("left", "right") for a0, a1 in win_z]
        for name, mat, ps in geom.room_shell(W, ROOM_H, D, openings):
            polys["floor" if name == "floor" else "plaster"] += _move(ps, 0.0, y0, 0.0)
        for lo, hi, skip in _partitions(rng, W, D):
            polys["plaster"] += _move(geom.box(lo, hi, skip), 0.0, y0, 0.0)
        hull_open += [(o[0], o[1], o[2], o[3] + y0 - WALL_T, o[4] + y0 - WALL_T, 0.0) for o in openings]
    Hs = (floors - 1) * FLOOR_H + ROOM_H
    for p in geom.hull(W, Hs, D, hull_open, T=WALL_T):
        n = geom.poly_normal(p)
        if n[1] < -0.5 and all(abs(q[1] + WALL_T) < 1e-9 for q in p):
            continue  # the underside, on the ground
        mat = "roof" if n[1] > 0.5 and all(abs(q[1] - Hs - WALL_T) < 1e-9 for q in p) else "facade"
        polys[mat] += _move([p], 0.0, WALL_T, 0.0)
    return W, D, floors, polys


def ground(x0, z0, lot):
    """A block's ground: the sidewalk around the lot (less the building's footprint `lot`,
    (x0, x1, z0, z1)) and the half streets on its sides, as quads facing up."""
    s0, s1 = STREET / 2, PITCH - STREET / 2
    walk = [geom.rect(1, 0.0, a, b, 1) for a, b in geom.cells_around((s0, s1), (s0, s1), [lot])]
    street = [geom.rect(1, 0.0, a, b, 1) for a, b in geom.cells_around((0.0, PITCH), (0.0, PITCH),
                                                                       [(s0, s1, s0, s1)])]
    return {"sidewalk": _move(walk, x0, 0.0, z0), "asphalt": _move(street, x0, 0.0, z0)}


def _r(x):
    return round(x, 4)


def _prims(w, mats, by_mat):
    out = []
    for mat in sorted(by_mat):
        if not by_mat[mat]:
            continue
        pos, nrm, idx, _ = geom.triangulate(by_mat[mat])
        out.append({"pos": [_r(x) for x in pos], "nrm": [_r(x) for x in nrm], "idx": idx, "material": mats[mat]})
    return out


def main():
    ap = argparse.ArgumentParser(description="write the scale bench's city level")
    ap.add_argument("--out", required=True, help="directory; writes city.gltf, city.bin, city.json")
    ap.add_argument("--fraction", type=float, default=1.0, help="the first F of the blocks (0 < F <= 1)")
    ap.add_argument("--blocks", type=int, default=16, help="blocks per side of the whole city")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--name", default="city")
    ap.add_argument("--stats-only", action="store_true", help="print the counts, write nothing")
    opt = ap.parse_args()
    if not (0 < opt.fraction <= 1) or opt.blocks < 1:
        sys.exit("gen_city: --fraction must be in (0, 1] and --blocks >= 1")
    total = opt.blocks * opt.blocks
    count = max(1, int(math.ceil(opt.fraction * total - 1e-9)))
    rng = random.Random(opt.seed)
    w = gltf_write.Writer()
    mats = {m: w.material(m, base=MATERIALS[m]) for m in sorted(MATERIALS)}
    tris = floors_total = 0
    area = 0.0
    # blocks in square shells from the corner, so the first k*k of them are a k x k district
    order = sorted(range(total), key=lambda i: (max(i % opt.blocks, i // opt.blocks), i // opt.blocks, i % opt.blocks))
    for b in range(count):
        bx, bz = order[b] % opt.blocks, order[b] // opt.blocks
        x0, z0 = bx * PITCH, bz * PITCH
        W, D, floors, polys = building(rng)
        ox = x0 + STREET / 2 + WALK + round(rng.random() * (PITCH - STREET - 2 * WALK - W - 2 * WALL_T), 2) + WALL_T
        oz = z0 + STREET / 2 + WALK + round(rng.random() * (PITCH - STREET - 2 * WALK - D - 2 * WALL_T), 2) + WALL_T
        ox, oz = max(ox, x0 + STREET / 2 + WALL_T), max(oz, z0 + STREET / 2 + WALL_T)
        polys = {m: _move(ps, ox, 0.0, oz) for m, ps in polys.items()}
        lot = (ox - WALL_T - x0, ox + W + WALL_T - x0, oz - WALL_T - z0, oz + D + WALL_T - z0)
        lot = (max(lot[0], STREET / 2), min(lot[1], PITCH - STREET / 2), max(lot[2], STREET / 2),
               min(lot[3], PITCH - STREET / 2))
        if not opt.stats_only:
            w.mesh("building_%03d" % b, _prims(w, mats, polys))
            w.mesh("ground_%03d" % b, _prims(w, mats, ground(x0, z0, lot)))
        floors_total += floors
        for ps in list(polys.values()) + list(ground(x0, z0, lot).values()):
            for p in ps:
                tris += len(p) - 2
                n = geom.poly_normal(p)
                a = [0.0, 0.0, 0.0]
                for i in range(len(p)):
                    c = geom.cross(p[i], p[(i + 1) % len(p)])
                    a = [a[k] + c[k] for k in range(3)]
                area += abs(geom.dot(a, n)) / 2
    path = os.path.join(opt.out, opt.name + ".gltf")
    if opt.stats_only:
        print("gen_city: %d buildings, %d floors, %d triangles, %.0f m2 of surface (not written)" % (
            count, floors_total, tris, area))
        return 0
    w.light("sun", "directional", 20.0, rotation=[_r(x) for x in geom.look_rotation(SUN_DIR)])
    os.makedirs(opt.out, exist_ok=True)
    w.save(path, external_bin=True, scene_extras={"lbk_sky": [0.6, 0.7, 0.9]})
    info = {"generator": "bench/scale/gen_city.py", "seed": opt.seed, "blocks": opt.blocks,
            "fraction": opt.fraction, "buildings": count, "floors": floors_total, "triangles": tris,
            "area_m2": round(area, 1)}
    with open(os.path.join(opt.out, opt.name + ".json"), "w") as f:
        json.dump(info, f, indent=1, sort_keys=True)
        f.write("\n")
    print("gen_city: %d buildings, %d floors, %d triangles, %.0f m2 of surface in %s" % (
        count, floors_total, tris, area, path))
    return 0


if __name__ == "__main__":
    sys.exit(main())
