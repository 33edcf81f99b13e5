"""The glossy-bounce scene (bake/transport/GGX.md): a closed room with a metal floor lit by one spot light
(plain Python 3; also runs inside Blender).

    python3 make_metal_room.py OUT.gltf [ROUGHNESS]     (default 0.1)

A 6 x 3 x 5 m room (y up, one-sided walls facing inwards, Lambertian plaster 0.75 and ceiling
0.8, metallicFactor 0 written explicitly) whose floor is a metal (metallic 1, base colour 0.9,
glTF roughness ROUGHNESS, alpha = roughness^2), and a Lambertian box (0.6) standing on it. The
spot light hangs near the left wall and points down and across the room, so the floor reflects
its cone in a lobe onto the right wall and the ceiling: the glossy-to-diffuse light that a
Lambertian baker gets wrong. No sky. Deterministic.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_write  # noqa: E402

W, H, D = 6.0, 3.0, 5.0


def box(lo, hi):
    """Quads of an axis-aligned box without its bottom, counter-clockwise seen from outside."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    return [
        [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],  # top
        [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)],  # -z
        [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],  # +z
        [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],  # -x
        [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],  # +x
    ]


def add(w, name, mat, quads):
    parts = [gltf_write.quad(*q) for q in quads]
    pos, nrm, idx = gltf_write.merge(parts)
    w.mesh(name, [{"pos": pos, "nrm": nrm, "idx": idx, "material": mat}])


def main():
    args = [a for a in sys.argv[sys.argv.index("--") + 1:]] if "--" in sys.argv else sys.argv[1:]
    out = args[0]
    rough = float(args[1]) if len(args) > 1 else 0.1
    w = gltf_write.Writer()
    plaster = w.material("plaster", base=(0.75, 0.75, 0.75))
    ceiling = w.material("ceiling", base=(0.8, 0.8, 0.8))
    metal = w.material("metal_floor", base=(0.9, 0.9, 0.9), metallic=1.0, roughness=rough)
    grey = w.material("box", base=(0.6, 0.6, 0.6))
    add(w, "floor", metal, [[(0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0)]])
    add(w, "ceiling", ceiling, [[(0, H, 0), (W, H, 0), (W, H, D), (0, H, D)]])
    add(w, "walls", plaster, [
        [(0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0)],      # z = 0, facing +z
        [(0, 0, D), (0, H, D), (W, H, D), (W, 0, D)],      # z = D, facing -z
        [(0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D)],      # x = 0, facing +x
        [(W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0)],      # x = W, facing -x
    ])
    add(w, "box", grey, box((3.6, 0.0, 3.2), (4.4, 0.8, 4.0)))
    # spot at (1.0, 2.7, 2.5), pointing at the floor point (2.6, 0, 2.5): the light travels along
    # d = (1.6, -2.7, 0)/|.|; glTF spots shine along their node's -z, so rotate -z onto d
    import math
    d = (1.6, -2.7, 0.0)
    n = math.sqrt(sum(x * x for x in d))
    d = tuple(x / n for x in d)
    # rotation taking a = (0, 0, -1) to d: axis a x d, angle acos(a . d)
    a = (0.0, 0.0, -1.0)
    ax = (a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0])
    s = math.sqrt(sum(x * x for x in ax))
    ang = math.acos(max(-1.0, min(1.0, sum(a[k] * d[k] for k in range(3)))))
    q = [ax[k] / s * math.sin(ang / 2) for k in range(3)] + [math.cos(ang / 2)]
    w.light("spot", "spot", 300.0, translation=(1.0, 2.7, 2.5), rotation=q,
            spot={"innerConeAngle": 0.3, "outerConeAngle": 0.5})
    w.save(out)
    print("make_metal_room: wrote %s (roughness %g)" % (out, rough))


main()
