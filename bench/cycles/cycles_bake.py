"""Cycles irradiance at lbk's receivers, by baking "sensors" (Blender Python).

    blender -b --factory-startup --python cycles_bake.py -- \
        --sensors S.tsv --out DIR [--scene X.gltf] [--sky R,G,B] [--threads N] \
        --runs SPP:SEED[,SPP:SEED...] [--equal-time SECONDS --clock cpu|wall --equal-seed S] \
        [--refs SPP:SEED,...] [--offset M]

S.tsv is texel_dump's output (or analytic.py's): one receiver per row with world position and
normal. Every receiver k gets a sensor: one tiny triangle at its position (raised `offset`
along the normal: --offset, else the header's sensor_offset, else 1e-4 of the receivers' extent), facing the normal, UV-mapped so that it covers the centre of exactly one
pixel (k mod W, k div W) of a float image, and invisible to diffuse, glossy, transmission,
volume and shadow rays, so the sensors neither occlude nor reflect (camera visibility stays on:
Cycles leaves an object invisible to every ray out of the bake, and a bake traces no camera
rays that could meet a sensor). Baking the
DIFFUSE pass with direct + indirect light and no colour writes, per pixel, the diffusely
reflected radiance divided by the albedo: irradiance / pi at the sensor. Each run bakes the
same image again at its own sample count and seed and writes DIR/run_SPP_SEED.f32 (float32
RGB irradiance = pixel * pi, one per receiver, in row order) and appends its wall and CPU
seconds (of the bake call itself: Cycles' scene sync, BVH build, sampling) to DIR/runs.json.
With --equal-time, a line t = a + b * spp is fitted to the --runs (the calibration) on the
chosen clock, and one more run bakes at the sample count that takes SECONDS; --refs run last.

Orientation: Blender's bake rasteriser covers a pixel whose centre ((i+0.5)/W, (j+0.5)/H) lies
inside a UV triangle, with v = 0 at the bottom of the image, and Image.pixels lists rows from
the bottom (v = 0) up. So sensor k is read at pixel index j*W + i. analytic.py proves this with
receivers of known, all different, irradiance (the rows read top-down instead do not match).
"""
import array
import json
import math
import os
import sys
import time

import bpy
import mathutils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_scene  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    a = {"scene": None, "sky": "0,0,0", "threads": "0", "runs": "16:1", "offset": "0", "sensors": None, "out": None,
         "bounces": "128", "equal_time": "0", "clock": "cpu", "equal_seed": "101", "refs": ""}
    i = 0
    while i < len(argv):
        k = argv[i].lstrip("-").replace("-", "_")
        if k not in a:
            raise SystemExit("cycles_bake.py: unknown option %s" % argv[i])
        a[k] = argv[i + 1]
        i += 2
    if not a["sensors"] or not a["out"]:
        raise SystemExit("cycles_bake.py: --sensors and --out are required")
    return a


def read_sensors(path):
    pos, nrm, offset = [], [], 0.0
    with open(path) as f:
        for line in f:
            if line.startswith("# sensor_offset "):
                offset = float(line.split()[2])
            if line.startswith("#") or not line.strip():
                continue
            c = line.split("\t")
            pos.append((float(c[6]), float(c[7]), float(c[8])))
            nrm.append((float(c[9]), float(c[10]), float(c[11])))
    return pos, nrm, offset


def image_size(n):
    w = max(1, int(math.ceil(math.sqrt(n))))
    return w, max(1, (n + w - 1) // w)


# The sensor triangle in pixel units around the pixel centre: it contains the centre (0, 0)
# well inside (0.5 px from every edge), and no other pixel centre (the neighbours' centres at
# (1, 0), (0, 1) lie beyond the hypotenuse u + v = 0.7), so each pixel has exactly one sensor.
TRI_UV = ((-0.4, -0.4), (1.1, -0.4), (-0.4, 1.1))


def build_sensors(pos, nrm, offset, size):
    n = len(pos)
    w, h = image_size(n)
    co = array.array("f", [0.0]) * (9 * n)
    uv = array.array("f", [0.0]) * (6 * n)
    for k in range(n):
        nn = mathutils.Vector(nrm[k]).normalized()
        a = mathutils.Vector((1, 0, 0)) if abs(nn.x) < 0.6 else mathutils.Vector((0, 1, 0))
        t = nn.cross(a).normalized()
        b = nn.cross(t)  # (t, b, n) right-handed: the triangle's winding normal is n
        c = mathutils.Vector(pos[k]) + offset * nn
        i, j = k % w, k // w
        for v, (du, dv) in enumerate(TRI_UV):
            p = c + size * (du * t + dv * b)
            co[9 * k + 3 * v: 9 * k + 3 * v + 3] = array.array("f", p)
            uv[6 * k + 2 * v] = (i + 0.5 + du) / w
            uv[6 * k + 2 * v + 1] = (j + 0.5 + dv) / h
    me = bpy.data.meshes.new("lbk_sensors")
    me.vertices.add(3 * n)
    me.vertices.foreach_set("co", co)
    me.loops.add(3 * n)
    me.loops.foreach_set("vertex_index", list(range(3 * n)))
    me.polygons.add(n)
    me.polygons.foreach_set("loop_start", list(range(0, 3 * n, 3)))
    me.polygons.foreach_set("loop_total", [3] * n)
    me.update(calc_edges=True)
    me.uv_layers.new(name="UVMap").data.foreach_set("uv", uv)
    img = bpy.data.images.new("lbk_sensor_image", w, h, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    mat = bpy.data.materials.new("lbk_sensor")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    for x in list(nodes):
        nodes.remove(x)
    out = nodes.new("ShaderNodeOutputMaterial")
    diff = nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Color"].default_value = (1, 1, 1, 1)
    diff.inputs["Roughness"].default_value = 0.0
    mat.node_tree.links.new(diff.outputs["BSDF"], out.inputs["Surface"])
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = img
    nodes.active = tex  # the bake target
    me.materials.append(mat)
    ob = bpy.data.objects.new("lbk_sensors", me)
    bpy.context.scene.collection.objects.link(ob)
    # camera visibility stays on: Cycles drops an object invisible to every ray from the bake,
    # and a bake traces no camera rays that could meet another sensor
    for attr in ("visible_diffuse", "visible_glossy", "visible_transmission",
                 "visible_volume_scatter", "visible_shadow"):
        setattr(ob, attr, False)
    return ob, img, w, h


def setup_cycles(scene, threads, bounces):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = bounces
    c.diffuse_bounces = bounces
    # glossy materials (Principled, gltf_scene.is_glossy): the sensors' diffuse rays must see
    # the light a metal reflects, i.e. diffuse -> glossy paths (Cycles' "reflective caustics")
    glossy = bool(scene.get("lbk_glossy", 0))
    c.glossy_bounces = bounces if glossy else 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    c.transparent_max_bounces = 8
    c.caustics_reflective = glossy
    c.blur_glossy = 0.0
    c.caustics_refractive = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0  # no probabilistic light culling
    c.use_animated_seed = False
    if threads > 0:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = threads
    b = scene.render.bake
    b.margin = 0
    b.use_clear = True
    b.target = "IMAGE_TEXTURES"


def bake(scene, ob, img, spp, seed):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    for o in scene.objects:
        o.select_set(o == ob)
    bpy.context.view_layer.objects.active = ob
    t0, c0 = time.perf_counter(), time.process_time()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0, use_clear=True,
                        target="IMAGE_TEXTURES")
    return time.perf_counter() - t0, time.process_time() - c0


def main():
    a = parse_args()
    os.makedirs(a["out"], exist_ok=True)
    scene = bpy.context.scene
    for o in list(bpy.data.objects):  # factory startup: cube, light, camera
        bpy.data.objects.remove(o)
    sky = tuple(float(x) for x in a["sky"].split(","))
    if a["scene"]:
        gltf_scene.load(a["scene"], scene, sky)
    else:
        gltf_scene.set_sky(scene, sky)
    pos, nrm, offset = read_sensors(a["sensors"])
    lo = [min(p[k] for p in pos) for k in range(3)]
    hi = [max(p[k] for p in pos) for k in range(3)]
    extent = max(max(hi[k] - lo[k] for k in range(3)), 1e-3)
    # raised 1e-4 of the level's size off the surface (1 mm in a 10 m room): far above float
    # rounding at these coordinates, far below any feature lbk resolves. texel_dump states the
    # offset it tested the sensors with (1e-4 of the scene's extent) in its header.
    offset = float(a["offset"]) or offset or 1e-4 * extent
    ob, img, w, h = build_sensors(pos, nrm, offset, offset / 4)
    setup_cycles(scene, int(a["threads"]), int(a["bounces"]))
    runs_path = os.path.join(a["out"], "runs.json")
    runs = json.load(open(runs_path)) if os.path.exists(runs_path) else []
    n = len(pos)
    px = array.array("f", [0.0]) * (w * h * 4)

    def one(spp, seed, role):
        wall, cpu = bake(scene, ob, img, spp, seed)
        img.pixels.foreach_get(px)
        out = array.array("f", [0.0]) * (3 * n)
        flipped = array.array("f", [0.0]) * (3 * n)
        for k in range(n):
            i, j = k % w, k // w
            q, qf = 4 * (j * w + i), 4 * ((h - 1 - j) * w + i)
            for ch in range(3):
                out[3 * k + ch] = px[q + ch] * math.pi
                flipped[3 * k + ch] = px[qf + ch] * math.pi
        name = "run_%d_%d.f32" % (spp, seed)
        with open(os.path.join(a["out"], name), "wb") as f:
            out.tofile(f)
        with open(os.path.join(a["out"], "flipped_" + name), "wb") as f:
            flipped.tofile(f)
        rec = {"spp": spp, "seed": seed, "role": role, "wall_s": wall, "cpu_s": cpu, "file": name, "sensors": n,
               "image": [w, h], "offset_m": offset, "threads": scene.render.threads}
        runs[:] = [r for r in runs if r["file"] != name] + [rec]
        print("cycles_bake: %s %d spp seed %d: %.2f s wall, %.2f s CPU (%d sensors)" % (role, spp, seed, wall, cpu, n))
        with open(runs_path, "w") as f:
            json.dump(runs, f, indent=1)
        return rec

    calib = [one(*(int(x) for x in spec.split(":")), "calibration") for spec in a["runs"].split(",") if spec]
    target = float(a["equal_time"])
    if target > 0:
        key = "cpu_s" if a["clock"] == "cpu" else "wall_s"
        xs, ys = [r["spp"] for r in calib], [r[key] for r in calib]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        sxx = sum((x - mx) ** 2 for x in xs)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else my / max(mx, 1)
        slope = max(slope, 1e-9)
        fixed = max(0.0, my - slope * mx)
        spp = max(1, int(round((target - fixed) / slope)))
        print("cycles_bake: time model %s = %.3f + %.5f * spp: %d spp for %.2f s" % (key, fixed, slope, spp, target))
        rec = one(spp, int(a["equal_seed"]), "equal_time")
        # the short calibration runs extrapolate; if the run missed the target by more than
        # 10 %, correct the per-sample cost from this run and bake once more (that one counts)
        if abs(rec[key] - target) > 0.1 * target and rec[key] > fixed:
            slope = (rec[key] - fixed) / spp
            spp2 = max(1, int(round((target - fixed) / slope)))
            if spp2 != spp:
                rec["role"] = "equal_time_first_try"
                print("cycles_bake: %.2f s instead of %.2f s: %d spp" % (rec[key], target, spp2))
                one(spp2, int(a["equal_seed"]) + 1, "equal_time")
    for spec in a["refs"].split(","):
        if spec:
            one(*(int(x) for x in spec.split(":")), "reference")

main()
