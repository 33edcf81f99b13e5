"""A glTF 2.0 scene rebuilt for Cycles the way lbk sees it (Blender Python; no add-on).

Why not Blender's glTF importer: it converts Y-up to Z-up, merges vertices, turns materials
into Principled BSDFs and converts lights with its own photometric constants. Here every glTF
node with a mesh becomes one Blender object whose vertices are transformed to world space in
glTF's own frame (Y up, metres: the axis convention does not matter to Cycles, and the sensor
positions of texel_dump are in the same frame), and:

  material  Diffuse BSDF (Lambert, roughness 0) of colour baseColorFactor x baseColorTexture
            (uv0, nearest texel, sRGB decoded), plus Emission of colour emissiveFactor x
            emissiveTexture and strength KHR_materials_emissive_strength (Cycles: an emission
            shader of colour C and strength S emits radiance C*S, checked by analytic.py).
            A material that is not doubleSided is black and non-emitting on its back side
            (as lbk: the back of a one-sided surface carries no radiance; it still occludes).
            Glossy materials (lbk's rule, bake/transport/GGX.md: metallicFactor > 0, glTF's
            default being 1, or a metallicRoughnessTexture) become a Principled BSDF instead:
            base colour as above, metallic and roughness = factor x texture (B, G; Non-Color),
            GGX (single scattering, as lbk), specular 0.5 (F0 = 0.04 for the dielectric part).
  lights    KHR_lights_punctual, converted by LIGHT_UNITS below (proved by analytic.py).
  sky       a uniform world colour of radiance `sky` (Background strength 1 = radiance 1).

Normal maps, transmission and alpha are ignored, as lbk ignores them.
"""
import array
import base64
import json
import math
import os
import struct
import tempfile

import bpy
import mathutils

# Cycles units for glTF's photometric ones, each checked against an analytic answer by
# analytic.py (see README.md). The Diffuse bake pass ("no colour") is irradiance / pi.
#   point:  Cycles point light of power P [W], radius 0: radiant intensity P / (4 pi) W/sr
#           -> P = 4 pi * I[cd]
#   spot:   a point light of P = 4 pi * I[cd] whose emission strength is the glTF cone (see
#           add_light: a Cycles spot light has another falloff)
#   sun:    Cycles sun strength = irradiance at normal incidence -> strength = E[lux]
LIGHT_UNITS = {"point": 4.0 * math.pi, "spot": 4.0 * math.pi, "directional": 1.0}

_COMPONENT = {5120: ("b", 1), 5121: ("B", 1), 5122: ("h", 2), 5123: ("H", 2), 5125: ("I", 4), 5126: ("f", 4)}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_NORM = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}


class Gltf:
    """Parsed JSON + buffers of a .gltf or .glb file."""

    def __init__(self, path):
        self.path = path
        self.dir = os.path.dirname(os.path.abspath(path))
        data = open(path, "rb").read()
        self.glb_bin = None
        if data[:4] == b"glTF":
            off = 12
            self.json = None
            while off + 8 <= len(data):
                length, kind = struct.unpack_from("<II", data, off)
                chunk = data[off + 8: off + 8 + length]
                if kind == 0x4E4F534A:
                    self.json = json.loads(chunk.decode("utf-8"))
                elif kind == 0x004E4942:
                    self.glb_bin = chunk
                off += 8 + length
        else:
            self.json = json.loads(data.decode("utf-8"))
        self.buffers = [self._load_buffer(b) for b in self.json.get("buffers", [])]

    def _load_uri(self, uri):
        if uri.startswith("data:"):
            return base64.b64decode(uri.split(",", 1)[1])
        from urllib.parse import unquote
        return open(os.path.join(self.dir, unquote(uri)), "rb").read()

    def _load_buffer(self, b):
        if "uri" not in b:
            return self.glb_bin
        return self._load_uri(b["uri"])

    def buffer_view(self, index):
        bv = self.json["bufferViews"][index]
        buf = self.buffers[bv["buffer"]]
        off = bv.get("byteOffset", 0)
        return buf, off, bv.get("byteLength", len(buf) - off), bv.get("byteStride", 0)

    def accessor(self, index):
        """Flat list of floats (or ints for indices) and the component count."""
        a = self.json["accessors"][index]
        if "sparse" in a:
            raise ValueError("sparse accessors are not supported")
        fmt, size = _COMPONENT[a["componentType"]]
        nc = _NCOMP[a["type"]]
        count = a["count"]
        if "bufferView" not in a:
            return [0.0] * (count * nc), nc
        buf, off, _, stride = self.buffer_view(a["bufferView"])
        off += a.get("byteOffset", 0)
        elem = size * nc
        if stride == 0 or stride == elem:
            out = list(struct.unpack_from("<%d%s" % (count * nc, fmt), buf, off))
        else:
            out = []
            for i in range(count):
                out.extend(struct.unpack_from("<%d%s" % (nc, fmt), buf, off + i * stride))
        if a.get("normalized") and fmt != "f":
            s = _NORM[a["componentType"]]
            out = [max(x / s, -1.0) for x in out]
        return out, nc


def _node_matrix(node):
    if "matrix" in node:
        m = node["matrix"]
        return mathutils.Matrix([[m[c * 4 + r] for c in range(4)] for r in range(4)])
    t = node.get("translation", [0, 0, 0])
    q = node.get("rotation", [0, 0, 0, 1])
    s = node.get("scale", [1, 1, 1])
    T = mathutils.Matrix.Translation(t)
    R = mathutils.Quaternion((q[3], q[0], q[1], q[2])).normalized().to_matrix().to_4x4()
    S = mathutils.Matrix.Diagonal((s[0], s[1], s[2], 1.0))
    return T @ R @ S


def world_nodes(g):
    """(node index, world matrix) for every node reachable from the default scene, depth first."""
    js = g.json
    scenes = js.get("scenes", [{"nodes": list(range(len(js.get("nodes", []))))}])
    roots = scenes[js.get("scene", 0)].get("nodes", [])
    out = []
    stack = [(r, mathutils.Matrix.Identity(4)) for r in reversed(roots)]
    while stack:
        n, parent = stack.pop()
        node = js["nodes"][n]
        m = parent @ _node_matrix(node)
        out.append((n, m))
        for c in reversed(node.get("children", [])):
            stack.append((c, m))
    return out


# ---- materials --------------------------------------------------------------------------

def _image(g, tex_index, cache, colorspace="sRGB"):
    key = (tex_index, colorspace)  # one Blender image per colour space (metallicRoughness: Non-Color)
    if key in cache:
        return cache[key]
    tex = g.json["textures"][tex_index]
    src = tex.get("source")
    img = None
    if src is not None:
        im = g.json["images"][src]
        if "uri" in im and not im["uri"].startswith("data:"):
            from urllib.parse import unquote
            img = bpy.data.images.load(os.path.join(g.dir, unquote(im["uri"])))
        else:
            data = g._load_uri(im["uri"]) if "uri" in im else None
            if data is None:
                buf, off, length, _ = g.buffer_view(im["bufferView"])
                data = buf[off: off + length]
            ext = ".png" if im.get("mimeType", "image/png") == "image/png" else ".jpg"
            fd, tmp = tempfile.mkstemp(suffix=ext)
            os.write(fd, data)
            os.close(fd)
            img = bpy.data.images.load(tmp)
            img.pack()
            os.unlink(tmp)
        img.colorspace_settings.name = colorspace
    cache[key] = img
    return img


def _texture_times(nodes, links, img, factor, uv_node):
    """An RGB socket = factor x texture(uv0), nearest texel (as lbk samples it)."""
    t = nodes.new("ShaderNodeTexImage")
    t.image = img
    t.interpolation = "Closest"
    t.extension = "REPEAT"
    links.new(uv_node.outputs["UV"], t.inputs["Vector"])
    mul = nodes.new("ShaderNodeMixRGB")
    mul.blend_type = "MULTIPLY"
    mul.inputs["Fac"].default_value = 1.0
    mul.inputs["Color1"].default_value = (factor[0], factor[1], factor[2], 1.0)
    links.new(t.outputs["Color"], mul.inputs["Color2"])
    return mul.outputs["Color"]


def is_glossy(gm):
    """lbk's rule (bake/transport/GGX.md): not Lambertian when metallicFactor (default 1) > 0 or
    a metallicRoughnessTexture is given; a material without pbrMetallicRoughness is the default
    (metallic 1, roughness 1)."""
    pbr = gm.get("pbrMetallicRoughness", {})
    return pbr.get("metallicFactor", 1.0) > 0 or "metallicRoughnessTexture" in pbr


def _principled(g, nodes, links, pbr, uv, cache):
    p = nodes.new("ShaderNodeBsdfPrincipled")
    p.distribution = "GGX"
    p.inputs["Specular"].default_value = 0.5
    p.inputs["Specular Tint"].default_value = 0.0
    p.inputs["Sheen"].default_value = 0.0
    p.inputs["Clearcoat"].default_value = 0.0
    p.inputs["Subsurface"].default_value = 0.0
    metal, rough = pbr.get("metallicFactor", 1.0), pbr.get("roughnessFactor", 1.0)
    p.inputs["Metallic"].default_value = metal
    p.inputs["Roughness"].default_value = rough
    mr = pbr.get("metallicRoughnessTexture")
    if mr is not None and mr.get("texCoord", 0) == 0:
        img = _image(g, mr["index"], cache, "Non-Color")
        if img is not None:
            t = nodes.new("ShaderNodeTexImage")
            t.image = img
            t.interpolation = "Closest"
            t.extension = "REPEAT"
            links.new(uv.outputs["UV"], t.inputs["Vector"])
            sep = nodes.new("ShaderNodeSeparateRGB")
            links.new(t.outputs["Color"], sep.inputs["Image"])
            for ch, factor, socket in (("B", metal, "Metallic"), ("G", rough, "Roughness")):
                m = nodes.new("ShaderNodeMath")
                m.operation = "MULTIPLY"
                m.inputs[1].default_value = factor
                links.new(sep.outputs[ch], m.inputs[0])
                links.new(m.outputs["Value"], p.inputs[socket])
    return p


def scene_is_glossy(g):
    """Whether any material Cycles builds for the glTF is glossy (a primitive without material
    gets the default one, which is)."""
    mats = g.json.get("materials", [])
    if any(is_glossy(m) for m in mats):
        return True
    return any("material" not in p for m in g.json.get("meshes", []) for p in m.get("primitives", []))


def lambert_material(g, mi, cache):
    """Blender material for glTF material mi (None: the glTF default material)."""
    gm = g.json["materials"][mi] if mi is not None else {}
    name = gm.get("name", "material%d" % mi if mi is not None else "default")
    mat = bpy.data.materials.new("lbk_" + name)
    mat.use_nodes = True
    nt = mat.node_tree
    nodes, links = nt.nodes, nt.links
    for n in list(nodes):
        nodes.remove(n)
    out = nodes.new("ShaderNodeOutputMaterial")
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = "UVMap"
    pbr = gm.get("pbrMetallicRoughness", {})
    base = pbr.get("baseColorFactor", [1, 1, 1, 1])
    if is_glossy(gm):
        diff = _principled(g, nodes, links, pbr, uv, cache)
    else:
        diff = nodes.new("ShaderNodeBsdfDiffuse")
        diff.inputs["Roughness"].default_value = 0.0
    diff.inputs["Base Color" if is_glossy(gm) else "Color"].default_value = (base[0], base[1], base[2], 1.0)
    if "baseColorTexture" in pbr and pbr["baseColorTexture"].get("texCoord", 0) == 0:
        img = _image(g, pbr["baseColorTexture"]["index"], cache)
        if img is not None:
            links.new(_texture_times(nodes, links, img, base, uv), diff.inputs["Base Color" if is_glossy(gm) else "Color"])
    front = diff.outputs["BSDF"]
    ef = gm.get("emissiveFactor", [0, 0, 0])
    strength = gm.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
    if max(ef) > 0 and strength > 0:
        em = nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (ef[0], ef[1], ef[2], 1.0)
        em.inputs["Strength"].default_value = strength
        if "emissiveTexture" in gm and gm["emissiveTexture"].get("texCoord", 0) == 0:
            img = _image(g, gm["emissiveTexture"]["index"], cache)
            if img is not None:
                links.new(_texture_times(nodes, links, img, ef, uv), em.inputs["Color"])
        add = nodes.new("ShaderNodeAddShader")
        links.new(front, add.inputs[0])
        links.new(em.outputs["Emission"], add.inputs[1])
        front = add.outputs["Shader"]
    if gm.get("doubleSided", False):
        links.new(front, out.inputs["Surface"])
    else:
        black = nodes.new("ShaderNodeBsdfDiffuse")
        black.inputs["Color"].default_value = (0, 0, 0, 1)
        geo = nodes.new("ShaderNodeNewGeometry")
        mix = nodes.new("ShaderNodeMixShader")
        links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
        links.new(front, mix.inputs[1])
        links.new(black.outputs["BSDF"], mix.inputs[2])
        links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return mat


# ---- meshes -----------------------------------------------------------------------------

def _flat_normals(pos, idx):
    n = [0.0] * len(pos)
    for t in range(0, len(idx), 3):
        a, b, c = idx[t], idx[t + 1], idx[t + 2]
        pa = mathutils.Vector(pos[3 * a: 3 * a + 3])
        e1 = mathutils.Vector(pos[3 * b: 3 * b + 3]) - pa
        e2 = mathutils.Vector(pos[3 * c: 3 * c + 3]) - pa
        f = e1.cross(e2)
        for v in (a, b, c):
            for k in range(3):
                n[3 * v + k] += f[k]
    return n


def build_mesh_object(g, node_index, world, materials, collection):
    js = g.json
    node = js["nodes"][node_index]
    mesh_def = js["meshes"][node["mesh"]]
    name = node.get("name") or "node%d" % node_index
    nmat = world.to_3x3().inverted_safe().transposed()
    flip = world.to_3x3().determinant() < 0
    co, nrm, uvs, loops, mats, slot_of = [], [], [], [], [], {}
    for prim in mesh_def["primitives"]:
        if prim.get("mode", 4) != 4:
            continue
        att = prim["attributes"]
        pos, _ = g.accessor(att["POSITION"])
        nv = len(pos) // 3
        idx = g.accessor(prim["indices"])[0] if "indices" in prim else list(range(nv))
        idx = [int(i) for i in idx]
        nn = g.accessor(att["NORMAL"])[0] if "NORMAL" in att else _flat_normals(pos, idx)
        uv0 = g.accessor(att["TEXCOORD_0"])[0] if "TEXCOORD_0" in att else [0.0] * (2 * nv)
        base = len(co) // 3
        for v in range(nv):
            p = world @ mathutils.Vector(pos[3 * v: 3 * v + 3])
            n = nmat @ mathutils.Vector(nn[3 * v: 3 * v + 3])
            n = n.normalized() if n.length > 0 else mathutils.Vector((0, 0, 1))
            co.extend(p)
            nrm.append(tuple(n))
            uvs.append((uv0[2 * v], 1.0 - uv0[2 * v + 1]))  # Blender v runs up, glTF v down
        mi = prim.get("material")
        if mi not in materials:
            materials[mi] = lambert_material(g, mi, materials.setdefault("_images", {}))
        slot = slot_of.setdefault(mi, len(slot_of))
        for t in range(0, len(idx), 3):
            a, b, c = idx[t], idx[t + 1], idx[t + 2]
            if a == b or b == c or a == c:
                continue  # zero area: nothing to light, nothing to hit
            if flip:
                b, c = c, b
            loops.extend((base + a, base + b, base + c))
            mats.append(slot)
    me = bpy.data.meshes.new(name)
    nv, nt = len(co) // 3, len(mats)
    me.vertices.add(nv)
    me.vertices.foreach_set("co", co)
    me.loops.add(3 * nt)
    me.loops.foreach_set("vertex_index", loops)
    me.polygons.add(nt)
    me.polygons.foreach_set("loop_start", list(range(0, 3 * nt, 3)))
    me.polygons.foreach_set("loop_total", [3] * nt)
    me.polygons.foreach_set("material_index", mats)
    me.polygons.foreach_set("use_smooth", [True] * nt)
    me.update(calc_edges=True)
    uvl = me.uv_layers.new(name="UVMap")
    flat = array.array("f", [0.0]) * (2 * 3 * nt)
    for i, v in enumerate(loops):
        flat[2 * i], flat[2 * i + 1] = uvs[v]
    uvl.data.foreach_set("uv", flat)
    me.use_auto_smooth = True
    me.normals_split_custom_set_from_vertices(nrm)
    for mi, slot in sorted(slot_of.items(), key=lambda kv: kv[1]):
        me.materials.append(materials[mi])
    ob = bpy.data.objects.new(name, me)
    collection.objects.link(ob)
    return ob


def _spot_cone_nodes(ld, axis, inner, outer):
    ld.use_nodes = True
    nt = ld.node_tree
    nodes, links = nt.nodes, nt.links
    em = nodes["Emission"]
    geo = nodes.new("ShaderNodeNewGeometry")
    dot = nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    links.new(geo.outputs["Normal"], dot.inputs[0])
    dot.inputs[1].default_value = (axis[0], axis[1], axis[2])
    co, ci = math.cos(outer), math.cos(inner)
    lin = nodes.new("ShaderNodeMath")
    lin.operation = "MULTIPLY_ADD"
    lin.use_clamp = True
    links.new(dot.outputs["Value"], lin.inputs[0])
    lin.inputs[1].default_value = 1.0 / max(0.001, ci - co)
    lin.inputs[2].default_value = -co / max(0.001, ci - co)
    sq = nodes.new("ShaderNodeMath")
    sq.operation = "MULTIPLY"
    links.new(lin.outputs["Value"], sq.inputs[0])
    links.new(lin.outputs["Value"], sq.inputs[1])
    links.new(sq.outputs["Value"], em.inputs["Strength"])


def add_light(light, world, collection, name):
    """A KHR_lights_punctual light at a node, in Cycles units (LIGHT_UNITS)."""
    kind = light["type"]
    col = light.get("color", [1, 1, 1])
    intensity = light.get("intensity", 1.0)
    if light.get("range", 0):
        print("gltf_scene: warning: light %s: range is ignored by Cycles (lbk fades it out)" % name)
    pos = world.to_translation()
    d = (world.to_3x3() @ mathutils.Vector((0, 0, -1))).normalized()
    if kind == "point":
        ld = bpy.data.lights.new(name, "POINT")
        ld.shadow_soft_size = 0.0
        ld.energy = intensity * LIGHT_UNITS["point"]
    elif kind == "spot":
        # A Cycles spot light is not a glTF spot: Cycles 3.4 multiplies its intensity by the
        # cosine to the axis and blends the edge with a smoothstep (analytic.py measured 0.963
        # inside the inner cone). So a glTF spot is a point light whose emission strength is
        # the glTF cone: t^2, t = clamp((cos a - cos outer) / (cos inner - cos outer)), as lbk
        # (bake/transport/shading.c); a = the angle between the light's axis and the direction
        # to the shaded point, which a light's shader sees as its Normal (world space).
        ld = bpy.data.lights.new(name, "POINT")
        ld.shadow_soft_size = 0.0
        spot = light.get("spot", {})
        outer = spot.get("outerConeAngle", math.pi / 4)
        inner = spot.get("innerConeAngle", 0.0)
        ld.energy = intensity * LIGHT_UNITS["spot"]
        _spot_cone_nodes(ld, d, inner, outer)
    elif kind == "directional":
        ld = bpy.data.lights.new(name, "SUN")
        ld.angle = 0.0
        ld.energy = intensity * LIGHT_UNITS["directional"]
    else:
        raise ValueError("unknown light type %s" % kind)
    ld.color = (col[0], col[1], col[2])
    ld.use_shadow = True
    ob = bpy.data.objects.new(name, ld)
    ob.location = pos
    ob.rotation_mode = "QUATERNION"
    ob.rotation_quaternion = d.to_track_quat("-Z", "Y")
    collection.objects.link(ob)
    return ob


def set_sky(scene, sky):
    world = bpy.data.worlds.new("lbk_sky")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (sky[0], sky[1], sky[2], 1.0)
    bg.inputs["Strength"].default_value = 1.0 if max(sky) > 0 else 0.0
    scene.world = world


def load(path, scene, sky=(0.0, 0.0, 0.0)):
    """Builds the glTF's meshes, materials and lights into `scene`; returns the mesh objects
    in lbk's object order (scene nodes depth first = bk_scene.objects)."""
    g = Gltf(path)
    col = bpy.data.collections.new("lbk_scene")
    scene.collection.children.link(col)
    materials, objects = {}, []
    lights = g.json.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    for n, m in world_nodes(g):
        node = g.json["nodes"][n]
        if "mesh" in node:
            objects.append(build_mesh_object(g, n, m, materials, col))
        li = node.get("extensions", {}).get("KHR_lights_punctual", {}).get("light")
        if li is not None:
            add_light(lights[li], m, col, lights[li].get("name") or "light%d" % li)
    set_sky(scene, sky)
    scene["lbk_glossy"] = 1 if scene_is_glossy(g) else 0
    return objects
