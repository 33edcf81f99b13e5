"""A minimal glTF 2.0 writer (plain Python 3, also usable inside Blender) for the bench's own
scenes: triangle meshes with POSITION, NORMAL, optional TEXCOORD_0/TEXCOORD_1, Lambert-style
materials (base colour, metallic/roughness factors, emission, emissive strength, doubleSided), KHR_lights_punctual lights
and node extras. One embedded base64 buffer, so a scene is one self-contained .gltf file."""
import base64
import json
import os
import struct


class Writer:
    def __init__(self):
        self.js = {"asset": {"version": "2.0", "generator": "lbk bench/cycles"}, "scene": 0,
                   "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "materials": [],
                   "accessors": [], "bufferViews": [], "buffers": []}
        self.bin = bytearray()
        self.lights = []

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        off = len(self.bin)
        self.bin.extend(data)
        self.js["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(data), "target": target})
        return len(self.js["bufferViews"]) - 1

    def _floats(self, values, ncomp, kind, minmax=False):
        data = struct.pack("<%df" % len(values), *values)
        acc = {"bufferView": self._view(data, 34962), "componentType": 5126, "count": len(values) // ncomp,
               "type": kind}
        if minmax:
            acc["min"] = [min(values[k::ncomp]) for k in range(ncomp)]
            acc["max"] = [max(values[k::ncomp]) for k in range(ncomp)]
        self.js["accessors"].append(acc)
        return len(self.js["accessors"]) - 1

    def _indices(self, idx):
        data = struct.pack("<%dI" % len(idx), *idx)
        self.js["accessors"].append({"bufferView": self._view(data, 34963), "componentType": 5125,
                                     "count": len(idx), "type": "SCALAR"})
        return len(self.js["accessors"]) - 1

    def material(self, name, base=(0.8, 0.8, 0.8), emission=(0, 0, 0), strength=1.0, double_sided=False,
                 metallic=0.0, roughness=1.0):
        """metallic 0 (written explicitly: glTF's default is 1) is a Lambertian surface to lbk."""
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [base[0], base[1], base[2], 1.0],
                                                    "metallicFactor": float(metallic),
                                                    "roughnessFactor": float(roughness)},
             "emissiveFactor": list(emission), "doubleSided": bool(double_sided)}
        if strength != 1.0:
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
            self.js.setdefault("extensionsUsed", [])
            if "KHR_materials_emissive_strength" not in self.js["extensionsUsed"]:
                self.js["extensionsUsed"].append("KHR_materials_emissive_strength")
        self.js["materials"].append(m)
        return len(self.js["materials"]) - 1

    def mesh(self, name, primitives, extras=None, translation=None):
        """primitives: list of dicts with pos (flat xyz), nrm (flat), idx, material, optional uv0/uv1
        (flat uv, glTF convention: v down). Adds a node instantiating the mesh; returns its index."""
        prims = []
        for p in primitives:
            att = {"POSITION": self._floats(p["pos"], 3, "VEC3", minmax=True),
                   "NORMAL": self._floats(p["nrm"], 3, "VEC3")}
            if p.get("uv0"):
                att["TEXCOORD_0"] = self._floats(p["uv0"], 2, "VEC2")
            if p.get("uv1"):
                att["TEXCOORD_1"] = self._floats(p["uv1"], 2, "VEC2")
            prims.append({"attributes": att, "indices": self._indices(p["idx"]), "material": p["material"]})
        self.js["meshes"].append({"name": name, "primitives": prims})
        node = {"name": name, "mesh": len(self.js["meshes"]) - 1}
        if extras:
            node["extras"] = extras
        if translation:
            node["translation"] = list(translation)
        return self._node(node)

    def light(self, name, kind, intensity, color=(1, 1, 1), translation=None, rotation=None, spot=None):
        l = {"name": name, "type": kind, "intensity": intensity, "color": list(color)}
        if spot:
            l["spot"] = spot
        self.lights.append(l)
        node = {"name": name, "extensions": {"KHR_lights_punctual": {"light": len(self.lights) - 1}}}
        if translation:
            node["translation"] = list(translation)
        if rotation:
            node["rotation"] = list(rotation)  # x, y, z, w
        return self._node(node)

    def _node(self, node):
        self.js["nodes"].append(node)
        i = len(self.js["nodes"]) - 1
        self.js["scenes"][0]["nodes"].append(i)
        return i

    def save(self, path, external_bin=False, scene_extras=None):
        """external_bin: the buffer goes to a .bin file beside PATH (same stem) instead of a base64
        data URI. scene_extras: the default scene's extras (e.g. lbk_sky)."""
        js = dict(self.js)
        if scene_extras:
            js["scenes"] = [dict(self.js["scenes"][0], extras=scene_extras)]
        if self.lights:
            js["extensions"] = {"KHR_lights_punctual": {"lights": self.lights}}
            js["extensionsUsed"] = list(js.get("extensionsUsed", [])) + ["KHR_lights_punctual"]
        if external_bin:
            bin_path = os.path.splitext(path)[0] + ".bin"
            with open(bin_path, "wb") as f:
                f.write(bytes(self.bin))
            uri = os.path.basename(bin_path)
        else:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()
        js["buffers"] = [{"byteLength": len(self.bin), "uri": uri}]
        with open(path, "w") as f:
            json.dump(js, f)


def quad(p0, p1, p2, p3):
    """Two triangles p0 p1 p2, p0 p2 p3 (counter-clockwise seen from the front) with flat normals."""
    e1 = [p1[k] - p0[k] for k in range(3)]
    e2 = [p2[k] - p0[k] for k in range(3)]
    n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
    ln = sum(x * x for x in n) ** 0.5
    n = [x / ln for x in n]
    pos = list(p0) + list(p1) + list(p2) + list(p3)
    return pos, n * 4, [0, 1, 2, 0, 2, 3]


def merge(parts):
    """Concatenates (pos, nrm, idx[, uv]) parts into one primitive's arrays."""
    pos, nrm, idx = [], [], []
    for p, n, i in parts:
        base = len(pos) // 3
        pos.extend(p)
        nrm.extend(n)
        idx.extend(base + x for x in i)
    return pos, nrm, idx
