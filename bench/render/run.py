#!/usr/bin/env python3
"""make bench-render: lbk render views of baked levels against converged Blender Cycles renders
of the same glTF (plain Python 3; Blender only as a subprocess). Definitions: README.md.

    python3 bench/render/run.py --lbk build/lbk --out build/bench-render [--harness DIR]
        [--ref-spp N] [--scenes DIR] [--images DIR] [--threads N]
"""
import argparse
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import time
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import exr  # noqa: E402

LUM = (0.2126, 0.7152, 0.0722)

# Views: camera position, target, vertical field of view (degrees). 160 x 120 pixels each.
SCENES = [
    {"name": "cornell_box", "file": "cornell_box/CornellBox-Original.gltf", "bake": ["--texel-density", "16"],
     "sky": None, "ref_spp": 1024, "views": [("front", (0, 1, 3.6), (0, 1, 0), 38), ("corner", (0.75, 1.6, 0.8), (-0.6, 0.4, -0.9), 70)]},
    {"name": "room_with_doors", "file": "room_with_doors/room.glb", "bake": ["--sky", "1,1,1"], "sky": (1, 1, 1),
     "ref_spp": 512,
     "views": [("hall", (0, 2.2, 4.6), (0, 2.0, -2), 70), ("corner", (4.4, 1.2, 4.4), (-1, 2.2, -1), 60)]},
]
LEAK = [("shared floor and walls", "leak_rooms.gltf"), ("separate rooms", "leak_rooms_split.gltf")]


def run(cmd, log):
    t0 = time.perf_counter()
    with open(log, "a") as f:
        f.write("$ %s\n" % " ".join(cmd))
        f.flush()
        p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if p.returncode:
        sys.exit("bench-render: %s failed (%d), see %s" % (cmd[0], p.returncode, log))
    return time.perf_counter() - t0


def luminance(path):
    w, h, c = exr.read(path)
    return w, h, [LUM[0] * r + LUM[1] * g + LUM[2] * b for r, g, b in zip(c["R"], c["G"], c["B"])]


def mse(a, b):
    return sum((x - y) ** 2 for x, y in zip(a, b)) / len(a)


def write_png(path, w, h, rgb, exposure):
    """8-bit sRGB PNG of linear rgb (3 floats per pixel) times exposure."""
    def srgb(x):
        x = min(max(x * exposure, 0.0), 1.0)
        return int(round(255 * (12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055)))
    raw = b"".join(b"\0" + bytes(srgb(v) for v in rgb[3 * w * y: 3 * w * (y + 1)]) for y in range(h))
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def rgb_of(path):
    w, h, c = exr.read(path)
    out = []
    for r, g, b in zip(c["R"], c["G"], c["B"]):
        out += (r, g, b)
    return w, h, out


def p99_exposure(lum):
    s = sorted(x for x in lum if x > 0 and math.isfinite(x))
    return 1.0 / s[int(0.99 * (len(s) - 1))] if s else 1.0


def view_metrics(d, v, w):
    """Everything of one row of the table (README.md "Metrics")."""
    _, _, l1 = luminance(d + "/lbk_seed1.exr")
    _, _, l2 = luminance(d + "/lbk_seed2.exr")
    _, _, ra = luminance(d + "/cycles_refA.exr")
    _, _, rb = luminance(d + "/cycles_refB.exr")
    _, _, eq = luminance(d + "/cycles_equal.exr")
    ref = [(a + b) / 2 for a, b in zip(ra, rb)]
    mean = sum(ref) / len(ref)
    var_ref = mse(ra, rb) / 4  # noise variance of the reference (the mean of two halves)
    noise2 = mse(l1, l2) / 2    # of one lbk bake
    both = [(a + b) / 2 for a, b in zip(l1, l2)]
    err = math.sqrt(max(0.0, mse(l1, ref) - var_ref)) / mean
    bias = math.sqrt(max(0.0, mse(both, ref) - noise2 / 2 - var_ref)) / mean
    worst = sorted(abs(a - b) for a, b in zip(l1, ref))
    p99 = worst[int(0.99 * (len(worst) - 1))] / mean
    median = worst[len(worst) // 2] / mean
    eq_err = math.sqrt(max(0.0, mse(eq, ref) - var_ref)) / mean
    _, _, s = exr.read(d + "/lbk_seams.exr", ("lightmapped", "seam"))
    jl, jr, pairs = [0.0, 0.0], [0.0, 0.0], [0, 0]  # all seams, flat seams (tools/render/seams.h)
    for i, bits in enumerate(s["seam"]):
        for shift, j in ((0, i + 1), (2, i + w)):
            b = int(bits) >> shift
            for k in (0, 1):
                if b & 1 and (k == 0 or b & 2):
                    jl[k] += abs(l1[i] - l1[j])
                    jr[k] += abs(ref[i] - ref[j])
                    pairs[k] += 1
    return {"mean_nits": mean, "rel_rmse": err, "noise": math.sqrt(noise2) / mean, "bias": bias, "p99": p99, "median": median,
            "ref_noise": math.sqrt(var_ref) / mean, "cycles_equal": eq_err,
            "seam_pairs": pairs[0], "seam_lbk": jl[0] / pairs[0] / mean if pairs[0] else 0.0,
            "seam_ref": jr[0] / pairs[0] / mean if pairs[0] else 0.0,
            "flat_pairs": pairs[1], "flat_lbk": jl[1] / pairs[1] / mean if pairs[1] else 0.0,
            "flat_ref": jr[1] / pairs[1] / mean if pairs[1] else 0.0}


def scene_views(a, sc, scenes_dir, log):
    gltf = os.path.join(scenes_dir, sc["file"])
    d0 = os.path.join(a.out, sc["name"])
    os.makedirs(d0, exist_ok=True)
    times = os.path.join(d0, "bake_seconds.json")
    if a.reuse and os.path.exists(times):
        bake_s = json.load(open(times))
    else:
        bake_s = [run([a.lbk, "bake", gltf, "-o", "%s/seed%d.lbk" % (d0, seed), "--seed", str(seed), "--threads",
                       str(a.threads), "-q"] + sc["bake"], log) for seed in (1, 2)]
        json.dump(bake_s, open(times, "w"))
    rows = []
    for name, frm, at, fov in sc["views"]:
        d = os.path.join(d0, name)
        os.makedirs(d, exist_ok=True)
        cam = ["--look-from", ",".join(map(str, frm)), "--look-at", ",".join(map(str, at)), "--fov", str(fov),
               "--size", "160x120", "--samples", "3", "--threads", str(a.threads), "-q"]
        if sc["sky"]:
            cam += ["--sky", ",".join(map(str, sc["sky"]))]
        for seed in (1, 2):
            extra = ["--seams", d + "/lbk_seams.exr"] if seed == 1 else []
            run([a.lbk, "render", gltf, "%s/seed%d.lbk" % (d0, seed), "-o", "%s/lbk_seed%d.exr" % (d, seed)] + cam +
                extra, log)
        half = max(1, int(sc["ref_spp"] * a.ref_scale) // 2)
        runs = "refA:%d:11,refB:%d:12,equal:1000000:3:%.3f" % (half, half, bake_s[0])
        done = a.reuse and all(os.path.exists(d + "/cycles_%s.exr" % k) for k in ("refA", "refB", "equal"))
        t = 0.0 if done else run([a.blender, "-b", "--factory-startup", "--python", os.path.join(HERE, "cycles_render.py"), "--",
                 "--harness", a.harness, "--scene", gltf, "--out", d, "--from", ",".join(map(str, frm)), "--at",
                 ",".join(map(str, at)), "--fov", str(fov), "--size", "160x120", "--threads", str(a.threads),
                 "--sky", ",".join(map(str, sc["sky"] or (0, 0, 0))), "--runs", runs], log)
        for k in ("refA", "refB", "equal"):
            if not done:
                shutil.move(d + "/%s.exr" % k, d + "/cycles_%s.exr" % k)
        m = view_metrics(d, name, 160)
        m["bake_s"] = bake_s[0]
        m["ref_spp"] = 2 * half
        m["cycles_ref_s"] = sum(json.load(open(d + "/%s.json" % k))["wall_s"] for k in ("refA", "refB"))
        m["cycles_equal_s"] = json.load(open(d + "/equal.json"))["wall_s"]
        m["blender_s"] = t
        rows.append((sc["name"], name, m))
        if a.images:
            w, h, lbk_rgb = rgb_of(d + "/lbk_seed1.exr")
            _, _, ra = rgb_of(d + "/cycles_refA.exr")
            _, _, rb = rgb_of(d + "/cycles_refB.exr")
            ref = [(x + y) / 2 for x, y in zip(ra, rb)]
            e = p99_exposure(luminance(d + "/cycles_refA.exr")[2])  # one exposure for both
            write_png(os.path.join(a.images, "%s_%s_lbk.png" % (sc["name"], name)), w, h, lbk_rgb, e)
            write_png(os.path.join(a.images, "%s_%s_cycles.png" % (sc["name"], name)), w, h, ref, e)
    return rows


def leak_scores(a, scenes_dir, log):
    out = []
    for label, f in LEAK:
        gltf = os.path.join(scenes_dir, f)
        d = os.path.join(a.out, "leak", os.path.splitext(f)[0])
        os.makedirs(d, exist_ok=True)
        run([a.lbk, "bake", gltf, "-o", d + "/level.lbk", "--threads", str(a.threads), "-q"], log)
        lum = []
        for cam in (0, 1):  # 0: in the lit room, 1: in the dark room (scenes/leak_rooms/README.md)
            run([a.lbk, "render", gltf, d + "/level.lbk", "--camera", str(cam), "-o", "%s/camera%d.exr" % (d, cam),
                 "--size", "160x120", "--probe-spheres", "6.8,1.5,1.2,0.3:4.5,1.5,3.0,0.25", "--threads",
                 str(a.threads), "-q"], log)
            lum.append(luminance("%s/camera%d.exr" % (d, cam))[2])
        lit = sum(lum[0]) / len(lum[0])
        out.append((label, lit, sum(lum[1]) / len(lum[1]) / lit, max(lum[1]) / lit,
                    sum(1 for x in lum[1] if x > 0) / len(lum[1])))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lbk", default="build/lbk")
    ap.add_argument("--out", default="build/bench-render")
    ap.add_argument("--harness", default=os.environ.get("LBK_CYCLES_HARNESS", os.path.join(HERE, "..", "cycles")))
    ap.add_argument("--blender", default=os.environ.get("BLENDER", "blender"))
    ap.add_argument("--scenes", default=os.environ.get("LBK_SCENES", "scenes"))
    ap.add_argument("--ref-scale", type=float, default=float(os.environ.get("LBK_REF_SCALE", "1")),
                    help="multiplies each scene's reference sample count")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--images", default=None, help="also write the README's PNGs here")
    ap.add_argument("--reuse", action="store_true", help="keep the bakes and Cycles renders already in --out")
    a = ap.parse_args()
    repo_scenes = os.path.join(HERE, "..", "..", "scenes", "leak_rooms")
    if shutil.which(a.blender) is None:
        print("SKIPPED bench-render (blender not installed: apt-get install blender)")
        return
    if not os.path.exists(os.path.join(a.harness, "gltf_scene.py")):
        print("SKIPPED bench-render (no Cycles harness at %s: set LBK_CYCLES_HARNESS to bench/cycles of the "
              "cycles branch)" % a.harness)
        return
    if not os.path.isdir(a.scenes):
        print("SKIPPED bench-render (no shared scenes at %s; set LBK_SCENES)" % a.scenes)
        return
    os.makedirs(a.out, exist_ok=True)
    if a.images:
        os.makedirs(a.images, exist_ok=True)
    log = os.path.join(a.out, "bench.log")
    open(log, "w").close()
    t0 = time.perf_counter()
    rows = []
    for sc in SCENES:
        rows += scene_views(a, sc, a.scenes, log)
    leaks = leak_scores(a, repo_scenes, log)
    print("lbk render vs Blender Cycles, 160x120, %d threads; errors relative to the view's mean luminance "
          "(bench/render/README.md)" % a.threads)
    print("%-16s %-7s %8s %8s %7s %7s %7s %7s %12s %7s %6s %8s" % (
        "scene", "view", "nits", "rel.RMSE", "noise", "bias", "median", "p99", "Cycles@eq.t", "bake s", "ref", "ref.nse"))
    for scene, view, m in rows:
        print("%-16s %-7s %8.4f %7.2f%% %6.2f%% %6.2f%% %6.2f%% %6.1f%% %11.2f%% %7.1f %6d %7.2f%%" % (
            scene, view, m["mean_nits"], 100 * m["rel_rmse"], 100 * m["noise"], 100 * m["bias"], 100 * m["median"],
            100 * m["p99"], 100 * m["cycles_equal"], m["bake_s"], m["ref_spp"], 100 * m["ref_noise"]))
    print("seams: mean luminance jump across chart boundaries (pixel pairs), lbk / reference, relative to the mean:")
    print("%-16s %-7s %22s %22s" % ("scene", "view", "all seams (pairs)", "flat seams (pairs)"))
    for scene, view, m in rows:
        print("%-16s %-7s %7.2f%% / %6.2f%% (%4d) %7.2f%% / %6.2f%% (%4d)" % (
            scene, view, 100 * m["seam_lbk"], 100 * m["seam_ref"], m["seam_pairs"], 100 * m["flat_lbk"],
            100 * m["flat_ref"], m["flat_pairs"]))
    print("leak (dark room seen from inside, relative to the lit room's mean luminance; must be 0):")
    for label, lit, mean, mx, frac in leaks:
        print("  %-24s lit room %.3f nits; dark room mean %.3g, max %.3g, %.1f%% of pixels > 0" % (
            label, lit, mean, mx, 100 * frac))
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump({"views": [{"scene": s, "view": v, **m} for s, v, m in rows],
                   "leak": [{"scene": l, "lit_nits": lit, "dark_mean": m, "dark_max": x, "dark_nonzero": fr}
                            for l, lit, m, x, fr in leaks]}, f, indent=1)
    print("bench-render: %.0f s; files in %s" % (time.perf_counter() - t0, a.out))


main()
