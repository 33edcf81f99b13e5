#!/usr/bin/env python3
"""lbk diff's calibration: the reseed study and the power table (make bench-diff).

Reseed study: for every scene of scenes/ (and room_sets_doors, _b and _c, light-set and
door levels that bench/door_scene_write.c generates, baked with --octahedral) and every preset,
PAIRS pairs of bakes that differ only in the seed (seeds 2i+1 and 2i+2), each pair compared with
`lbk diff --json` in noise mode. An *item* is what lbk diff gives one verdict: a compared object
(class "texels" when lightmapped, "llg" for an LLG object), the GLG, OCTP, and each light set
("set_texels", "set_probes") or door state or combination ("door_texels", "door_probes") in each
target space. Every item of a reseed pair that is beyond noise is a false alarm. Per preset and
class it prints: items, false alarms, the measured rate and its 95 % upper bound
(Clopper-Pearson; 3/n when none), the stated rate (--false-alarm, default 0.001), and the
calibration margins: the largest |z|/k_mean, chroma_z/k_chroma and, for the sample count, the
largest significant/critical, with the measured sample rate against the class's p0 and the RMS
of the samples' normalised deviation (1 when the per-sample noise model is right).

Power (--power): variants of the base bake (sky +2 %, sky +5 %, one light +5 %, one material's
albedo +10 %, a hue change of one material at the same luminance, one door's state: its panel slid
out of the doorway), PAIRS each with its own seed against a base seed, and the share of pairs lbk
diff calls DIFFERENT, per class (share of pairs in which some item of the class is beyond noise).

Usage: diff_reseed.py --lbk build/lbk --out DIR [--pairs 20] [--presets fast,high]
                      [--scenes a,b] [--false-alarm 0.001] [--power] [--door-scene-tool T]
Bakes already in DIR are reused (the same file name means the same scene, preset, seed, variant).
"""
import argparse
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
GENERATED = None  # a scene written by scene_file()
ROOT = os.path.dirname(HERE)
SCENES = {
    # name: (file under scenes/, extra bake options)
    "cornell_box": ("cornell_box/CornellBox-Original.gltf", []),
    "cornell_box_bjs": ("cornell_box_bjs/cornellBox-2.80-Eevee-gltf.gltf", []),
    "lights_punctual_lamp": ("lights_punctual_lamp/LightsPunctualLamp.gltf", []),
    "room_with_doors": ("room_with_doors/room.glb", ["--sky", "1,1,1"]),
    "leak_rooms": ("leak_rooms/leak_rooms.gltf", []),
    "water_bottle_draco": ("water_bottle_draco/WaterBottle.gltf", []),
    # generated into OUT/scenes by --door-scene-tool (bench/door_scene_write.c): light sets A and B,
    # the door "north", and the octahedral volume, so the set, door and octp classes have items.
    # The classes' factors were set on room_sets_doors; room_sets_doors_b (a second door, a
    # combination state, a sun) was held out until it showed the high-pass reading correlated noise
    # low (the fix was made on it); room_sets_doors_c is held out now: it only reports.
    "room_sets_doors": (GENERATED, ["--octahedral"]),
    "room_sets_doors_b": (GENERATED, ["--octahedral"]),
    "room_sets_doors_c": (GENERATED, ["--octahedral"]),
}
GENERATED_ARGS = {"room_sets_doors": [], "room_sets_doors_b": ["b"], "room_sets_doors_c": ["c"]}
CLASSES = ["texels", "glg", "llg", "octp", "set_texels", "set_probes", "door_texels", "door_probes"]


BAKER = None


def scene_file(args, name):
    """The scene's glTF: under scenes/, or the generated light-set and door level written once to
    OUT/scenes by --door-scene-tool."""
    f = SCENES[name][0]
    if f is not GENERATED:
        return os.path.join(ROOT, "scenes", f)
    if not args.door_scene_tool:
        sys.exit(f"scene {name} needs --door-scene-tool (make bench-diff builds bench/door_scene_write.c)")
    path = os.path.join(args.out, "scenes", name + ".gltf")
    if not os.path.exists(path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        r = subprocess.run([args.door_scene_tool, path + ".tmp"] + GENERATED_ARGS[name], cwd=ROOT, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"{args.door_scene_tool} failed: {r.stderr}")
        os.replace(path + ".tmp", path)
    return path


def bake(lbk, out, scene_file, extra, preset, seed, tag):
    path = os.path.join(out, f"{tag}_{preset}_s{seed}.lbk")
    if not os.path.exists(path):
        cmd = [BAKER or lbk, "bake", scene_file, "-o", path + ".tmp", "--seed", str(seed), "--preset", preset] + extra
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"bake failed: {' '.join(cmd)}\n{r.stderr}")
        os.replace(path + ".tmp", path)
    return path


def diff(lbk, a, b, alpha):
    r = subprocess.run([lbk, "diff", a, b, "--json", "--false-alarm", str(alpha)], capture_output=True, text=True)
    if r.returncode not in (0, 1):
        sys.exit(f"lbk diff {a} {b} failed ({r.returncode}): {r.stderr}")
    return json.loads(r.stdout)


def items(d):
    """(class, name, noise) of every item lbk diff judged."""
    out = []
    for o in d.get("objects", []):
        if o.get("noise"):
            out.append((o["noise"]["class"], o["name"], o["noise"]))
    for key in ("glg", "octp"):
        n = d.get(key, {}).get("noise")
        if n:
            out.append((n["class"], key, n))
    for s in d.get("light_sets", []):
        for sp, n in (s.get("noise") or {}).items():
            if n:
                out.append((n["class"], f"{s['name']}/{sp}", n))
    return out


def upper95(k, n):
    """Clopper-Pearson one-sided 95 % upper bound of a rate with k events in n trials (bisection)."""
    if n == 0:
        return float("nan")
    if k >= n:
        return 1.0

    def cdf(p):  # P(X <= k)
        return sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))

    lo, hi = k / n, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        if cdf(mid) > 0.05:
            lo = mid
        else:
            hi = mid
    return hi


class Tally:
    def __init__(self):
        self.items = self.alarms = 0
        self.zmax = self.cmax = self.smax = 0.0
        self.sig = self.count = self.extreme = 0
        self.u2 = 0.0
        self.where = []
        self.mde_l, self.mde_c = [], []

    def add(self, n, model, where):
        self.items += 1
        if not n["within_noise"]:
            self.alarms += 1
            self.where.append(where)
        z = abs(n["z"]) if n["z"] is not None else float("inf")
        self.zmax = max(self.zmax, z / model["k_mean"])
        cz = n["chroma"]["z"] if n["chroma"]["z"] is not None else float("inf")
        self.cmax = max(self.cmax, cz / model["k_chroma"])
        tested = n.get("tested", n["count"])  # the count test's N (samples whose noise was measured)
        crit = n["share_limit"] * tested + 1
        if n.get("count_test", True):
            self.smax = max(self.smax, n["significant"] / crit)
        self.extreme += n.get("extreme", 0)
        self.mde_l.append(model["k_mean"] * n["noise"]["mean"])
        if n["chroma"]["noise"] is not None:
            self.mde_c.append(model["k_chroma"] * n["chroma"]["noise"])
        self.sig += n["significant"]
        self.count += tested
        if n.get("sample_rms") is not None:
            self.u2 += n["sample_rms"] ** 2 * tested


def reseed_study(args, lbk, presets, scenes):
    ok = True
    print(f"reseed study: {args.pairs} pairs (seeds 2i+1, 2i+2) per scene and preset, stated false-alarm rate "
          f"{args.false_alarm} per item")
    print("item: a compared object (texels or llg), the GLG, OCTP, a light set or door state per target space")
    for preset in presets:
        tallies = {c: Tally() for c in CLASSES}
        model = None
        for name in scenes:
            src, extra = scene_file(args, name), SCENES[name][1]
            for i in range(args.pairs):
                a = bake(lbk, args.out, src, extra, preset, 2 * i + 1, name)
                b = bake(lbk, args.out, src, extra, preset, 2 * i + 2, name)
                d = diff(lbk, a, b, args.false_alarm)
                model = d["noise_model"] or model
                if d["mode"] != "noise":
                    sys.exit(f"{a}: not in noise mode ({d['mode_reason']})")
                for cls, item, n in items(d):
                    tallies[cls].add(n, d["noise_model"], f"{name} s{2*i+1}/{2*i+2} {item}")
        print(f"\npreset {preset}: {len(scenes)} scenes x {args.pairs} pairs")
        print(f"{'class':<11} {'items':>6} {'alarms':>6} {'rate':>8} {'95% up':>8} {'stated':>7} "
              f"{'|z|/k':>6} {'chr/k':>6} {'cnt/crit':>8} {'smp rate':>8} {'p0':>6} {'u rms':>6} {'extreme':>8}")
        for c in CLASSES:
            t = tallies[c]
            if t.items == 0:
                print(f"{c:<11} {0:>6}  (no such items)")
                continue
            rate = t.alarms / t.items
            p0 = model["classes"][c]["sample_rate"] if model else float("nan")
            print(f"{c:<11} {t.items:>6} {t.alarms:>6} {rate:>8.4f} {upper95(t.alarms, t.items):>8.4f} "
                  f"{args.false_alarm:>7g} {t.zmax:>6.2f} {t.cmax:>6.2f} {t.smax:>8.2f} "
                  f"{t.sig / max(t.count, 1):>8.4f} {p0:>6.3f} {math.sqrt(t.u2 / max(t.count, 1)):>6.2f} "
                  f"{t.extreme / max(t.count, 1):>8.5f}")
            ml, mc = sorted(t.mde_l), sorted(t.mde_c)
            if ml and mc:
                print(f"{'':<11} smallest detectable: luminance shift {ml[len(ml) // 2] * 100:.1f} % (median item; "
                      f"best {ml[0] * 100:.1f} %), chromaticity {mc[len(mc) // 2] * 100:.1f} % (best {mc[0] * 100:.1f} %)")
            for w in t.where[:5]:
                print(f"    false alarm: {w}")
            ok = ok and rate <= args.false_alarm
    return ok


def variant_scene(out, scene_dir, gltf_name, tag, edit):
    """A copy of scene_dir under out/variants/tag with edit(json) applied to its .gltf."""
    import shutil
    dst = os.path.join(out, "variants", tag)
    if not os.path.exists(os.path.join(dst, gltf_name)):
        shutil.rmtree(dst, ignore_errors=True)
        shutil.copytree(scene_dir, dst)
        with open(os.path.join(scene_dir, gltf_name)) as f:
            doc = json.load(f)
        edit(doc)
        with open(os.path.join(dst, gltf_name), "w") as f:
            json.dump(doc, f)
    return os.path.join(dst, gltf_name)


def material(doc, name):
    return next(m for m in doc["materials"] if m.get("name") == name)


def scale_albedo(name, f):
    def edit(doc):
        c = material(doc, name)["pbrMetallicRoughness"]["baseColorFactor"]
        c[:3] = [min(1.0, v * f) for v in c[:3]]
    return edit


def set_albedo(name, rgb):
    def edit(doc):
        material(doc, name)["pbrMetallicRoughness"]["baseColorFactor"][:3] = rgb
    return edit


def scale_light(index, f):
    def edit(doc):
        doc["extensions"]["KHR_lights_punctual"]["lights"][index]["intensity"] *= f
    return edit


def slide_door(name, dx):
    """The door's panel moved dx metres along x, out of its doorway (a pocket door left open)."""
    def edit(doc):
        node = next(n for n in doc["nodes"] if n.get("extras", {}).get("lbk_door") == name)
        t = node.setdefault("translation", [0, 0, 0])
        t[0] += dx
    return edit


# (name, scene, how): how is ("sky", factor) on a sky-lit scene or ("gltf", edit)
VARIANTS = [
    ("sky +2 %", "room_with_doors", ("sky", 1.02)),
    ("sky +5 %", "room_with_doors", ("sky", 1.05)),
    ("light +5 % (Point)", "lights_punctual_lamp", ("gltf", scale_light(0, 1.05))),
    ("light +20 % (Point)", "lights_punctual_lamp", ("gltf", scale_light(0, 1.20))),
    ("albedo +10 % (cornell leftWall)", "cornell_box", ("gltf", scale_albedo("leftWall", 1.10))),
    ("hue: rightWall green -> cyan-blue, same luminance", "cornell_box",
     ("gltf", set_albedo("rightWall", [0.14, 0.40, 0.58]))),
    ("door state: north door slid open 2.6 m", "room_sets_doors", ("gltf", slide_door("north", 2.6))),
]


def power_study(args, lbk, presets, scenes):
    pairs = args.power_pairs or args.pairs
    print(f"\npower: {pairs} pairs per variant (base seed 2i+1 against the variant baked with seed 1000+i);"
          " detected = lbk diff DIFFERENT; per class the share of pairs with an item of that class beyond noise")
    for preset in presets:
        print(f"\npreset {preset}")
        print(f"{'variant':<50} {'detected':>9}  classes (share of pairs)")
        for label, name, how in VARIANTS:
            if name not in scenes:
                continue
            src, extra = scene_file(args, name), SCENES[name][1]
            tag = "v" + "".join(ch for ch in label if ch.isalnum())[:24]
            if how[0] == "sky":
                sky = ",".join(str(how[1]) for _ in range(3))
                vfile, vextra = src, [a if a != "1,1,1" else sky for a in extra] if "--sky" in extra else extra + ["--sky", sky]
            else:
                vfile, vextra = variant_scene(args.out, os.path.dirname(src), os.path.basename(src), tag, how[1]), extra
            hits, per = 0, {}
            for i in range(pairs):
                a = bake(lbk, args.out, src, extra, preset, 2 * i + 1, name)
                b = bake(lbk, args.out, vfile, vextra, preset, 1000 + i, f"{name}_{tag}")
                d = diff(lbk, a, b, args.false_alarm)
                hits += not d["equal"]
                seen = {cls for cls, _, n in items(d) if not n["within_noise"]}
                for cls in seen:
                    per[cls] = per.get(cls, 0) + 1
            cl = ", ".join(f"{c} {per[c] / pairs:.2f}" for c in CLASSES if c in per) or "none"
            print(f"{label:<50} {hits:>4}/{pairs:<4}  {cl}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lbk", default=os.path.join(ROOT, "build", "lbk"))
    ap.add_argument("--lbk-bake", help="the lbk that bakes (default --lbk)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--pairs", type=int, default=20)
    ap.add_argument("--presets", default="fast,high")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--door-scene-tool", help="bench/door_scene_write (for the room_sets_doors scene)")
    ap.add_argument("--false-alarm", type=float, default=0.001)
    ap.add_argument("--power", action="store_true")
    ap.add_argument("--power-only", action="store_true", help="skip the reseed study")
    ap.add_argument("--power-pairs", type=int, help="pairs per power variant (default --pairs)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    global BAKER
    BAKER = args.lbk_bake
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in SCENES:
            sys.exit(f"unknown scene {s} (known: {', '.join(SCENES)})")
    presets = args.presets.split(",")
    ok = True if args.power_only else reseed_study(args, args.lbk, presets, scenes)
    if args.power or args.power_only:
        power_study(args, args.lbk, presets, scenes)
    print("\nreseed study:", "every class at or under its stated rate" if ok else "SOME CLASS OVER ITS STATED RATE")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
