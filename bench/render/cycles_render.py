"""Camera renders of a glTF level with Blender Cycles, for the lbk render bench (Blender Python).

    blender -b --factory-startup --python cycles_render.py -- --harness DIR --scene X.gltf \
        --out DIR --from X,Y,Z --at X,Y,Z [--up X,Y,Z] --fov DEG --size WxH [--sky R,G,B] \
        [--threads N] --runs NAME:SPP:SEED[:SECONDS],...

The scene is rebuilt by the Cycles harness's converter (DIR/gltf_scene.py, bench/cycles on the
cycles branch: Lambert materials from the glTF's base colour, emission in nits, KHR lights in
Cycles units, the uniform sky as the world colour; its README proves the units). Each run
renders the camera view at SPP samples and SEED (SECONDS > 0: Cycles' time limit instead, with
SPP as the cap) into DIR/NAME.exr (linear radiance, float, ZIP) and records its wall seconds in
DIR/NAME.json. Film: box pixel filter one pixel wide (the same pixel integral as lbk render's
stratified rays), no denoising, no adaptive sampling, no clamping, diffuse bounces 128 and
Russian roulette (unbiased), Standard view transform (EXR stays scene-linear anyway).
"""
import json
import math
import os
import sys
import time

import bpy
import mathutils


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    a = {"harness": None, "scene": None, "out": None, "from": None, "at": None, "up": "0,1,0", "fov": "60",
         "size": "160x120", "sky": "0,0,0", "threads": "0", "runs": "", "bounces": "128"}
    for i in range(0, len(argv), 2):
        k = argv[i].lstrip("-")
        if k not in a or i + 1 >= len(argv):
            raise SystemExit("cycles_render.py: bad option %s" % argv[i])
        a[k] = argv[i + 1]
    for k in ("harness", "scene", "out", "from", "at", "runs"):
        if not a[k]:
            raise SystemExit("cycles_render.py: --%s is required" % k)
    return a


def vec(s):
    return mathutils.Vector(tuple(float(x) for x in s.split(",")))


def camera(scene, frm, at, up, fov):
    """A Blender camera looks down its local -Z with +Y up: columns (right, up, -forward)."""
    f = (at - frm).normalized()
    r = f.cross(up).normalized()
    u = r.cross(f)
    m = mathutils.Matrix(((r.x, u.x, -f.x, frm.x), (r.y, u.y, -f.y, frm.y), (r.z, u.z, -f.z, frm.z), (0, 0, 0, 1)))
    cd = bpy.data.cameras.new("lbk_camera")
    cd.sensor_fit = "VERTICAL"
    cd.angle_y = math.radians(fov)
    cd.clip_start = 1e-3
    cd.clip_end = 1e5
    ob = bpy.data.objects.new("lbk_camera", cd)
    ob.matrix_world = m
    scene.collection.objects.link(ob)
    scene.camera = ob


def setup(scene, w, h, threads, bounces):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = c.diffuse_bounces = bounces
    c.glossy_bounces = c.transmission_bounces = c.volume_bounces = 0
    c.transparent_max_bounces = 8
    c.caustics_reflective = c.caustics_refractive = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.use_animated_seed = False
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.film_transparent = False
    r.use_persistent_data = True  # the BVH is built once for every run of the session
    if threads > 0:
        r.threads_mode = "FIXED"
        r.threads = threads
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    im = r.image_settings
    im.file_format = "OPEN_EXR"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    im.color_mode = "RGB"


def main():
    a = parse_args()
    sys.path.insert(0, os.path.abspath(a["harness"]))
    import gltf_scene  # the Cycles harness's converter (bench/cycles)

    os.makedirs(a["out"], exist_ok=True)
    scene = bpy.context.scene
    for o in list(bpy.data.objects):  # factory startup: cube, light, camera
        bpy.data.objects.remove(o)
    sky = tuple(float(x) for x in a["sky"].split(","))
    gltf_scene.load(a["scene"], scene, sky)
    w, h = (int(x) for x in a["size"].split("x"))
    setup(scene, w, h, int(a["threads"]), int(a["bounces"]))
    camera(scene, vec(a["from"]), vec(a["at"]), vec(a["up"]), float(a["fov"]))
    for spec in a["runs"].split(","):
        f = spec.split(":")
        name, spp, seed = f[0], int(f[1]), int(f[2])
        limit = float(f[3]) if len(f) > 3 else 0.0
        scene.cycles.samples = spp
        scene.cycles.seed = seed
        scene.cycles.time_limit = limit
        scene.render.filepath = os.path.join(a["out"], name + ".exr")
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        wall = time.perf_counter() - t0
        rec = {"name": name, "spp": spp, "seed": seed, "time_limit": limit, "wall_s": wall,
               "threads": scene.render.threads}
        with open(os.path.join(a["out"], name + ".json"), "w") as fp:
            json.dump(rec, fp)
        print("cycles_render: %s %d spp seed %d%s: %.2f s" % (name, spp, seed,
              " (time limit %.2f s)" % limit if limit > 0 else "", wall))


main()
