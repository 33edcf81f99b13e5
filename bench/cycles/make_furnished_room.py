"""The many-small-charts scene: a furnished room lit only by the sky through one window, with
lightmap UVs (TEXCOORD_1) from Blender's Lightmap Pack (Blender Python).

    blender -b --factory-startup --python make_furnished_room.py -- OUT.gltf

A 6 x 3 x 5 m room (y up, zero-thickness one-sided walls facing inwards) with a 2.2 x 1.4 m
window in the +z wall; inside a table, four chairs, a sofa, a bookshelf with 16 books, a
cabinet, crates, a rug, a window sill and a picture frame, 36 objects in all. Every object's
UV1 is its own Lightmap Pack layout (one chart per quad face: most charts are a few texels at
lbk's 8 texels/m), like the held-out level where lbk measured 7-8x Cycles' error. Faces that
rest on another surface (the bottoms of grounded boxes) are left out, as a level would.
Deterministic: the same Blender version writes the same file.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_write  # noqa: E402

# faces of an axis-aligned box, counter-clockwise seen from outside
_FACES = {
    "bottom": ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)),
    "top": ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),
    "back": ((0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)),     # -z
    "front": ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)),    # +z
    "left": ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)),     # -x
    "right": ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)),    # +x
}


def box(lo, hi, skip=()):
    quads = []
    for name, corners in _FACES.items():
        if name in skip:
            continue
        quads.append([tuple(lo[k] + c[k] * (hi[k] - lo[k]) for k in range(3)) for c in corners])
    return quads


def rect_x(z, x0, x1, y0, y1, inward):  # wall at constant z, facing -z if inward == "-z"
    q = [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)]
    return q if inward == "+z" else q[::-1]


def rect_z(x, z0, z1, y0, y1, inward):  # wall at constant x
    q = [(x, y0, z1), (x, y0, z0), (x, y1, z0), (x, y1, z1)]
    return q if inward == "+x" else q[::-1]


def level():
    """(name, material, quads) per object."""
    W, H, D = 6.0, 3.0, 5.0
    wx0, wx1, wy0, wy1 = 2.0, 4.2, 0.9, 2.3  # the window in the z = D wall
    objs = [
        ("floor", "wood", [[(0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0)]]),
        ("ceiling", "ceiling", [[(0, H, 0), (W, H, 0), (W, H, D), (0, H, D)]]),
        ("wall_back", "plaster", [rect_x(0.0, 0, W, 0, H, "+z")]),
        ("wall_left", "plaster", [rect_z(0.0, 0, D, 0, H, "+x")]),
        ("wall_right", "plaster", [rect_z(W, 0, D, 0, H, "-x")]),
        ("wall_window", "plaster", [rect_x(D, 0, wx0, 0, H, "-z"), rect_x(D, wx1, W, 0, H, "-z"),
                                    rect_x(D, wx0, wx1, 0, wy0, "-z"), rect_x(D, wx0, wx1, wy1, H, "-z")]),
    ]
    # table: top and four legs
    t = box((2.2, 0.72, 2.0), (3.8, 0.76, 2.9))
    for lx, lz in ((2.25, 2.05), (3.7, 2.05), (2.25, 2.8), (3.7, 2.8)):
        t += box((lx, 0, lz), (lx + 0.05, 0.72, lz + 0.05), skip=("bottom", "top"))
    objs.append(("table", "oak", t))
    # four chairs: seat, back, two side panels
    for i, (cx, cz, facing) in enumerate(((2.6, 1.55, -1), (3.4, 1.55, -1), (2.6, 3.35, 1), (3.4, 3.35, 1))):
        x0, z0 = cx - 0.21, cz - 0.21
        c = box((x0, 0.43, z0), (x0 + 0.42, 0.47, z0 + 0.42))
        bz = z0 if facing < 0 else z0 + 0.39
        c += box((x0, 0.47, bz), (x0 + 0.42, 0.92, bz + 0.03), skip=("bottom",))
        c += box((x0, 0, z0), (x0 + 0.03, 0.43, z0 + 0.42), skip=("bottom", "top"))
        c += box((x0 + 0.39, 0, z0), (x0 + 0.42, 0.43, z0 + 0.42), skip=("bottom", "top"))
        objs.append(("chair_%d" % (i + 1), "oak", c))
    # sofa against the right wall
    s = box((5.0, 0, 1.0), (5.9, 0.42, 3.0), skip=("bottom",))
    s += box((5.7, 0.42, 1.0), (5.95, 0.85, 3.0), skip=("bottom",))
    s += box((5.0, 0.42, 0.8), (5.95, 0.62, 1.0), skip=("bottom",))
    s += box((5.0, 0.42, 3.0), (5.95, 0.62, 3.2), skip=("bottom",))
    objs.append(("sofa", "fabric", s))
    # bookshelf against the left wall: two sides, top, four shelves
    sx0, sx1, sz0, sz1, sh = 0.02, 0.34, 1.0, 2.2, 2.0
    b = box((sx0, 0, sz0), (sx1, sh, sz0 + 0.02), skip=("bottom",))
    b += box((sx0, 0, sz1 - 0.02), (sx1, sh, sz1), skip=("bottom",))
    b += box((sx0, sh - 0.02, sz0 + 0.02), (sx1, sh, sz1 - 0.02))
    shelves = (0.05, 0.5, 0.95, 1.4)
    for y in shelves:
        b += box((sx0, y, sz0 + 0.02), (sx1, y + 0.02, sz1 - 0.02))
    objs.append(("bookshelf", "oak", b))
    # books: 4 per shelf, different sizes
    k = 0
    for si, y in enumerate(shelves):
        z = sz0 + 0.06 + 0.11 * si
        for j in range(4):
            hgt = 0.2 + 0.03 * ((k * 7) % 5)
            thick = 0.04 + 0.01 * ((k * 3) % 4)
            objs.append(("book_%02d" % (k + 1), ("red", "blue", "paper")[k % 3],
                         box((0.06, y + 0.02, z), (0.28, y + 0.02 + hgt, z + thick), skip=("bottom",))))
            z += thick + 0.03 + 0.05 * (j % 2)
            k += 1
    objs.append(("cabinet", "white", box((0.05, 0, 3.6), (0.5, 0.9, 4.4), skip=("bottom",))))
    for i, (x, z, e) in enumerate(((4.4, 0.3, 0.5), (4.95, 0.35, 0.4), (4.6, 0.3, 0.35))):
        y0 = 0.0 if i < 2 else 0.5
        objs.append(("crate_%d" % (i + 1), "crate", box((x, y0, z), (x + e, y0 + e, z + e), skip=("bottom",))))
    objs.append(("rug", "fabric_red", box((1.9, 0, 1.3), (4.1, 0.012, 3.6), skip=("bottom",))))
    objs.append(("window_sill", "white", box((wx0 - 0.05, wy0 - 0.04, D - 0.18), (wx1 + 0.05, wy0, D), skip=("front",))))
    objs.append(("picture", "frame", box((2.0, 1.4, 0.0), (3.2, 2.2, 0.03), skip=("back",))))
    return objs


MATERIALS = {
    "wood": (0.45, 0.30, 0.18), "ceiling": (0.85, 0.85, 0.85), "plaster": (0.78, 0.76, 0.72),
    "oak": (0.55, 0.40, 0.25), "fabric": (0.25, 0.35, 0.5), "red": (0.6, 0.1, 0.08), "blue": (0.1, 0.15, 0.5),
    "paper": (0.8, 0.78, 0.7), "white": (0.85, 0.85, 0.82), "crate": (0.6, 0.5, 0.3), "fabric_red": (0.5, 0.12, 0.1),
    "frame": (0.3, 0.25, 0.2),
}


def lightmap_pack(quads):
    """Blender's Lightmap Pack of these quads (one object): per quad corner a (u, v)."""
    me = bpy.data.meshes.new("lm")
    verts = [c for q in quads for c in q]
    me.from_pydata(verts, [], [tuple(range(4 * i, 4 * i + 4)) for i in range(len(quads))])
    me.uv_layers.new(name="lightmap")
    ob = bpy.data.objects.new("lm", me)
    bpy.context.scene.collection.objects.link(ob)
    for o in bpy.context.scene.objects:
        o.select_set(o == ob)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.lightmap_pack(PREF_CONTEXT="ALL_FACES", PREF_PACK_IN_ONE=False, PREF_NEW_UVLAYER=False,
                             PREF_BOX_DIV=12, PREF_MARGIN_DIV=0.2)
    bpy.ops.object.mode_set(mode="OBJECT")
    uv = [(d.uv[0], d.uv[1]) for d in me.uv_layers["lightmap"].data]
    bpy.data.objects.remove(ob)
    bpy.data.meshes.remove(me)
    return uv


def main():
    out = sys.argv[sys.argv.index("--") + 1]
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    w = gltf_write.Writer()
    mats = {name: w.material(name, base=c) for name, c in MATERIALS.items()}
    for name, mat, quads in level():
        uv = lightmap_pack(quads)
        pos, nrm, idx, uv1 = [], [], [], []
        for qi, q in enumerate(quads):
            p, n, i = gltf_write.quad(*q)
            base = len(pos) // 3
            pos += p
            nrm += n
            idx += [base + x for x in i]
            for c in range(4):
                u, v = uv[4 * qi + c]
                uv1 += [u, 1.0 - v]  # glTF v runs down
        w.mesh(name, [{"pos": pos, "nrm": nrm, "idx": idx, "material": mats[mat], "uv1": uv1}])
    w.save(out)
    print("make_furnished_room: wrote %s" % out)


main()
