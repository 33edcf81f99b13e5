#!/usr/bin/env python3
"""Writes leak_rooms.gltf: two rooms side by side under one roof, a lit one and a closed dark one,
built the way levels usually are, so light has every chance to leak (README.md):

  room A (lit)  x 0 .. 4,    y 0 .. 3, z 0 .. 4, a 200 cd point light at (2, 2.2, 2);
  divider       a solid wall x 4.0 .. 4.2 from floor to ceiling and wall to wall;
  room B (dark) x 4.2 .. 8.2: no light, no opening; a small prop (a 0.6 m box, lbk_lighting "llg").

The floor, the ceiling and the two long walls are single quads running through both rooms and
under / past the divider (the texels and the triangles there straddle it). Every surface is
Lambert grey 0.6, one-sided, facing into the rooms. Camera 0 looks at the divider from room A,
camera 1 from room B. Deterministic: `python3 make_leak_rooms.py` rewrites the same bytes."""
import base64
import json
import os
import struct

GREY = [0.6, 0.6, 0.6, 1.0]


def quad(p0, p1, p2, p3):
    """Counter-clockwise seen from the front; normal from the winding."""
    e1 = [p1[k] - p0[k] for k in range(3)]
    e2 = [p3[k] - p0[k] for k in range(3)]
    n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    ln = sum(x * x for x in n) ** 0.5
    return [p0, p1, p2, p3], [x / ln for x in n]


def box(mn, mx, inward):
    x0, y0, z0 = mn
    x1, y1, z1 = mx
    faces = [  # outward, counter-clockwise seen from outside
        [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],
        [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)],
        [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
        [(x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)],
        [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)],
        [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
    ]
    return [quad(*(f[::-1] if inward else f)) for f in faces]


class Gltf:
    def __init__(self):
        self.js = {"asset": {"version": "2.0", "generator": "lbk scenes/leak_rooms/make_leak_rooms.py"},
                   "scene": 0, "scenes": [{"name": "leak_rooms", "nodes": []}], "nodes": [], "meshes": [],
                   "materials": [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": GREY,
                                                                           "metallicFactor": 0.0}}],
                   "accessors": [], "bufferViews": [], "buffers": [], "cameras": [],
                   "extensionsUsed": ["KHR_lights_punctual"],
                   "extensions": {"KHR_lights_punctual": {"lights": []}}}
        self.bin = bytearray()

    def _accessor(self, fmt, values, ncomp, kind, target, minmax=False):
        off = len(self.bin)
        self.bin += struct.pack("<%d%s" % (len(values), fmt), *values)
        self.js["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(self.bin) - off,
                                       "target": target})
        acc = {"bufferView": len(self.js["bufferViews"]) - 1, "componentType": 5126 if fmt == "f" else 5125,
               "count": len(values) // ncomp, "type": kind}
        if minmax:
            acc["min"] = [min(values[k::ncomp]) for k in range(ncomp)]
            acc["max"] = [max(values[k::ncomp]) for k in range(ncomp)]
        self.js["accessors"].append(acc)
        return len(self.js["accessors"]) - 1

    def node(self, entry):
        self.js["nodes"].append(entry)
        self.js["scenes"][0]["nodes"].append(len(self.js["nodes"]) - 1)

    def mesh(self, name, quads, lighting):
        pos, nrm, idx = [], [], []
        for corners, n in quads:
            base = len(pos) // 3
            for c in corners:
                pos += c
                nrm += n
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
        att = {"POSITION": self._accessor("f", pos, 3, "VEC3", 34962, True),
               "NORMAL": self._accessor("f", nrm, 3, "VEC3", 34962)}
        prim = {"attributes": att, "indices": self._accessor("I", idx, 1, "SCALAR", 34963), "material": 0}
        self.js["meshes"].append({"name": name, "primitives": [prim]})
        self.node({"name": name, "mesh": len(self.js["meshes"]) - 1, "extras": {"lbk_lighting": lighting}})

    def camera(self, name, frm, at, yfov):
        """A node at frm whose -Z looks at `at` (no roll: +Y stays up)."""
        f = [at[k] - frm[k] for k in range(3)]
        ln = sum(x * x for x in f) ** 0.5
        f = [x / ln for x in f]
        import math
        yaw = math.atan2(-f[0], -f[2])
        pitch = math.asin(f[1])
        cy, sy, cp, sp = math.cos(yaw / 2), math.sin(yaw / 2), math.cos(pitch / 2), math.sin(pitch / 2)
        q = [cy * sp, sy * cp, -sy * sp, cy * cp]  # yaw about +Y, then pitch about the new +X
        self.js["cameras"].append({"name": name, "type": "perspective",
                                   "perspective": {"yfov": yfov, "znear": 0.01, "aspectRatio": 4 / 3}})
        self.node({"name": name, "camera": len(self.js["cameras"]) - 1, "translation": list(frm),
                   "rotation": [round(x, 7) for x in q]})

    def point_light(self, name, pos, candela):
        lights = self.js["extensions"]["KHR_lights_punctual"]["lights"]
        lights.append({"name": name, "type": "point", "color": [1, 1, 1], "intensity": candela})
        self.node({"name": name, "translation": list(pos), "extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}})

    def write(self, path):
        self.js["buffers"] = [{"byteLength": len(self.bin),
                               "uri": "data:application/octet-stream;base64," + base64.b64encode(self.bin).decode()}]
        with open(path, "w") as f:
            json.dump(self.js, f, indent=1, sort_keys=True)
            f.write("\n")


def level(split):
    g = Gltf()
    if split:  # each room its own closed box: no triangle crosses the divider
        g.mesh("room_a", box((0.0, 0.0, 0.0), (4.0, 3.0, 4.0), inward=True), "lightmap")
        g.mesh("room_b", box((4.2, 0.0, 0.0), (8.2, 3.0, 4.0), inward=True), "lightmap")
    else:  # floor, ceiling and long walls span both rooms, the divider stands on the floor
        g.mesh("shell", box((0.0, 0.0, 0.0), (8.2, 3.0, 4.0), inward=True), "lightmap")
        g.mesh("divider", box((4.0, 0.0, 0.0), (4.2, 3.0, 4.0), inward=False)[:2], "lightmap")  # the other faces
        # would lie inside the shell's
    prop = box((5.9, 0.0, 1.7), (6.5, 0.6, 2.3), inward=False)
    g.mesh("prop", prop[:2] + prop[3:], "llg")  # no bottom face
    g.point_light("lamp", (2.0, 2.2, 2.0), 200.0)
    g.camera("lit_room", (0.3, 1.6, 3.7), (4.0, 1.0, 1.2), 1.2)
    g.camera("dark_room", (7.9, 1.6, 3.7), (4.2, 1.0, 1.2), 1.2)
    return g


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    level(False).write(os.path.join(here, "leak_rooms.gltf"))
    level(True).write(os.path.join(here, "leak_rooms_split.gltf"))


main()
