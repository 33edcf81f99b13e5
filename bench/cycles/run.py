"""make bench-cycles: lbk against Blender Cycles at equal time, per scene and object.

For each scene: lbk bakes it (twice, seeds 1 and 2: the second only measures lbk's own noise);
texel_dump lists every receiver (lightmap texel: world point, normal, decoded irradiance; LLG
prop: vertices); Cycles bakes sensors at those receivers (cycles_bake.py) in one Blender
session: two short calibration runs fit its time per sample, one run at the sample count that
takes as long as lbk's bake, then the reference: two long runs with different seeds, whose
mean is the reference and whose difference measures its noise. Errors are luminance relative
RMSE = RMSE / mean over the receivers both cover, with the reference's own noise removed in
quadrature (sqrt(max(0, MSE - sigma_ref^2))). README.md describes it all and the units.

Environment (or the options of the same name): LBK (lbk binary), LBK_TEXEL_DUMP (texel_dump
built from the same tree), BLENDER, LBK_SCENES (scenes), CYCLES_CLOCK (cpu|wall: the
clock "equal time" is measured on, default cpu), LBK_BENCH_QUICK=1 (references 8x shorter),
BENCH_CYCLES_SCENES (comma-separated subset), BENCH_CYCLES_THREADS (default: all cores),
LBK_ALT (a second lbk binary, e.g. an experiment, baked with seed 1 and measured against the same
references: extra columns; it must give the same receivers; default: LBK itself with
--adaptive off, so every run shows what adaptive sampling buys; "none": no second baker),
LBK_ALT_DUMP (its texel_dump, default LBK_TEXEL_DUMP), LBK_ALT_NAME (its column label, default
"alt", or "adaptive off" for the default). BENCH_CYCLES_LEVELS / --levels MANIFEST: the scenes
are those of a bench/levels manifest instead (its folder holds the glTFs; every row and scene
header carries the level's set, family and layout; bench/levels/README.md).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import analytic  # noqa: E402
import common  # noqa: E402

# Reference sample counts: each was chosen so the reference's own noise is well below lbk's
# error on that scene (it is measured and printed every run), within the ~15 min budget of
# `make bench` on the 2-core machine. calib: the two short runs that fit Cycles' time per sample.
SCENES = [
    {"name": "cornell_box", "gltf": "{scenes}/cornell_box/CornellBox-Original.gltf", "lbk": [], "sky": (0, 0, 0),
     "ref_spp": 4096, "calib": (16, 64)},
    {"name": "room_with_doors", "gltf": "{scenes}/room_with_doors/room.glb", "lbk": ["--sky", "1,1,1"],
     "sky": (1, 1, 1), "ref_spp": 512, "calib": (4, 16)},
    {"name": "furnished_room", "gltf": "{work}/furnished_room.gltf", "lbk": ["--sky", "1,1,1"], "sky": (1, 1, 1),
     "ref_spp": 2048, "calib": (8, 32), "make": "make_furnished_room.py"},
    # the glossy-bounce scene: a metal floor (metallic 1, roughness r) under a spot light; bake/transport/GGX.md.
    # Written by plain Python (make_python); the other roughnesses only on request
    # (BENCH_CYCLES_SCENES=metal_room_r0.05,...)
    {"name": "metal_room_r0.1", "gltf": "{work}/metal_room_r0.1.gltf", "lbk": [], "sky": (0, 0, 0),
     "ref_spp": 4096, "calib": (16, 64), "make": "make_metal_room.py", "make_python": True, "make_args": ["0.1"]},
] + [{"name": "metal_room_r%g" % r, "gltf": "{work}/metal_room_r%g.gltf" % r, "lbk": [], "sky": (0, 0, 0),
      "ref_spp": 4096, "calib": (16, 64), "make": "make_metal_room.py", "make_python": True,
      "make_args": ["%g" % r], "on_request": True} for r in (0.05, 0.2, 0.4)]


def levels_scenes(manifest):
    """The scenes of a bench/levels manifest (gen_levels.py), in its order, as SCENES entries."""
    d = json.load(open(manifest))
    base = os.path.dirname(os.path.abspath(manifest))
    out = []
    for e in d["scenes"]:
        sc = {"name": e["name"], "gltf": os.path.join(base, e["gltf"]), "lbk": list(e["lbk_args"]),
              "sky": tuple(e["sky"]), "ref_spp": e["cycles"]["ref_spp"], "calib": tuple(e["cycles"]["calib"]),
              "ref_spp_quick": e["cycles"].get("ref_spp_quick")}
        sc["tags"] = {k: e[k] for k in ("set", "level", "family", "layout", "lighting", "density",
                                        "texel_density", "thin_m")}
        out.append(sc)
    return out


def density_args(lbk_args):
    return lbk_args[lbk_args.index("--texel-density"): lbk_args.index("--texel-density") + 2] \
        if "--texel-density" in lbk_args else []


class Group:
    """Error statistics of one set of receivers (luminance)."""

    def __init__(self, idx, lbk1, lbk2, ref1, ref2, cyc):
        n = len(idx)
        self.n = n
        ref = [(ref1[i] + ref2[i]) / 2 for i in idx]
        self.mean = sum(ref) / n
        var_ref = sum((ref1[i] - ref2[i]) ** 2 for i in idx) / (4 * n)  # noise variance of the mean of two
        ms_ref = sum(r * r for r in ref) / n
        m = self.mean if self.mean > 0 else float("nan")

        def mse(x):
            return sum((x[i] - r) ** 2 for i, r in zip(idx, ref)) / n

        def err(*xs):  # several bakes (lbk's two seeds): the root of their mean squared error
            return math.sqrt(max(0.0, sum(mse(x) for x in xs) / len(xs) - var_ref)) / m

        def err_rms(*xs):  # normalised like lbk's estimate: RMSE / RMS of the values
            return math.sqrt(max(0.0, sum(mse(x) for x in xs) / len(xs) - var_ref)) / \
                math.sqrt(max(1e-300, ms_ref - var_ref))
        self.ref_noise = math.sqrt(var_ref) / m
        # lbk's or Cycles' measured MSE is mostly the reference's own noise: not resolved
        self.unresolved = min((mse(lbk1) + mse(lbk2)) / 2, mse(cyc)) < 2 * var_ref
        # lbk's error and bias: the mean over its two seeds' bakes, each against the reference. One
        # bake's error swings far more between seeds than Cycles' does (a bake's cache noise is
        # shared by all its texels: the Cornell box 7.0-10.2 % from one seed to the next, its
        # mean over 12 seeds 10.2 %); two halve that variance (README, How it works, 5).
        self.lbk = err(lbk1, lbk2)
        self.lbk_bias = sum((lbk1[i] + lbk2[i]) / 2 - r for i, r in zip(idx, ref)) / n / m
        self.lbk_noise = math.sqrt(sum((lbk1[i] - lbk2[i]) ** 2 for i in idx) / (2 * n)) / m
        self.cyc = err(cyc)
        self.lbk_rms = err_rms(lbk1, lbk2)
        self.lbk_noise_rms = math.sqrt(sum((lbk1[i] - lbk2[i]) ** 2 for i in idx) / (2 * n)) / \
            math.sqrt(max(1e-300, ms_ref - var_ref))


def pct(x):
    return "%6.1f %%" % (100 * x) if x == x else "    n/a"


def bake_lbk(sc, work, opt, seed, alt=False):
    out = os.path.join(work, "%s.seed%d%s.lbk" % (sc["name"], seed, ".alt" if alt else ""))
    rep = out + ".json"
    cmd = [opt.alt if alt else opt.lbk, "bake", sc["path"], "-o", out, "--json-report", rep, "--seed", str(seed),
           "--threads", str(opt.threads)] + sc["lbk"]
    wall, cpu = common.run_timed(cmd, out + ".log")
    tsv = out + ".tsv"
    common.run_timed([opt.alt_dump if alt else opt.dump, sc["path"], out, tsv] + density_args(sc["lbk"]) +
                     ["--footprint", str(opt.footprint)], tsv + ".log")
    return common.Receivers(tsv), wall, cpu, json.load(open(rep))


def run_scene(sc, work, opt, out):
    t_scene = time.perf_counter()
    sc = dict(sc)
    sc["path"] = sc["gltf"].format(scenes=opt.scenes, work=work)
    gen = os.path.join(common.HERE, sc.get("make", ""))
    if sc.get("make") and (not os.path.exists(sc["path"]) or os.path.getmtime(gen) > os.path.getmtime(sc["path"])):
        if sc.get("make_python"):
            common.run_timed([sys.executable, gen, sc["path"]] + sc.get("make_args", []), sc["path"] + ".log")
        else:
            common.run_timed([common.blender(), "-b", "--factory-startup", "--python",
                              gen, "--", sc["path"]], sc["path"] + ".log")
    rec, lbk_wall, lbk_cpu, report = bake_lbk(sc, work, opt, 1)
    rec2, _, _, _ = bake_lbk(sc, work, opt, 2)
    if rec2.pos != rec.pos:
        sys.exit("bench-cycles: %s: the seed-2 bake has other receivers" % sc["name"])
    # the second baker (LBK_ALT), seed 1, against the same references
    alt_lum, alt_lum2, alt_txt = None, None, ""
    if opt.alt:
        reca, alt_wall, alt_cpu, _ = bake_lbk(sc, work, opt, 1, alt=True)
        reca2, _, _, _ = bake_lbk(sc, work, opt, 2, alt=True)
        if reca.pos != rec.pos or reca.flags != rec.flags or reca2.pos != rec.pos:
            sys.exit("bench-cycles: %s: the %s bake has other receivers (LBK_ALT must share the layout)" % (
                sc["name"], opt.alt_name))
        alt_lum = [common.lum(x) for x in reca.rgb]
        alt_lum2 = [common.lum(x) for x in reca2.rgb]
        alt_txt = "; alt = %s: %.1f s wall, %.1f s CPU (%s spp, estimated error %.1f %%)" % (
            opt.alt_name, alt_wall, alt_cpu, reca.meta.get("spp", "?"), 100 * float(reca.meta.get("est_rel_rmse", "nan")))
    target = lbk_cpu if opt.clock == "cpu" else lbk_wall
    # The reference is each texel's defined value (TRANSPORT.md, Footprint): the mean over its
    # footprint's K x K points (README "Footprint sensors"), each point at half the reference's
    # samples (with K = 2: twice the cost of one point at the full count). Cycles at equal time
    # bakes one point per texel, as a Cycles lightmap bake samples a texel (at one position).
    fp_points = max(1.0, rec.sensors / len(rec))
    ref_spp = max(64, int(sc["ref_spp"] * (0.5 if fp_points > 1 else 1)) // (8 if opt.quick else 1))
    if opt.quick and sc.get("ref_spp_quick"):  # a levels manifest's own quick count (bench/levels/README.md)
        ref_spp = max(64, int(sc["ref_spp_quick"] * (0.5 if fp_points > 1 else 1)))
    tsv = os.path.join(work, "%s.seed1.lbk.tsv" % sc["name"])
    points_tsv = tsv + ".points"
    common.write_point_sensors(tsv, points_tsv)
    cdir = os.path.join(work, sc["name"] + ".cycles")
    runs = common.run_cycles(sc["path"], points_tsv, cdir, [(s, 11 + i) for i, s in enumerate(sc["calib"])],
                             sky=sc["sky"], threads=opt.threads, equal_time=target, clock=opt.clock)
    # The two references: from the seed-1 bake's rows (footprint points at the stratum centres), or,
    # BENCH_CYCLES_JITTER=1, with the points jittered in their strata, each reference from its own
    # points (jitter seeds 1 and 2), so that their mean is the footprint mean and their
    # difference, the reference noise, holds the quadrature's spread too (README, Footprint sensors).
    by_role = {}
    jittered = fp_points > 1 and opt.jitter
    for rseeds in (((1,), (2,)) if jittered else ((1, 2),)):
        rtsv = "%s.ref%d" % (tsv, rseeds[0]) if jittered else tsv
        if jittered:
            common.run_timed([opt.dump, sc["path"], os.path.join(work, "%s.seed1.lbk" % sc["name"]), rtsv] +
                             density_args(sc["lbk"]) + ["--footprint", str(opt.footprint), "--jitter",
                                                        str(rseeds[0])], rtsv + ".log")
        rr = common.Receivers(rtsv) if jittered else rec
        if rr.pos != rec.pos:
            sys.exit("bench-cycles: %s: the reference sensors %s have other receivers" % (sc["name"], rtsv))
        rdir = os.path.join(work, sc["name"] + ".cycles-ref" + ("%d" % rseeds[0] if jittered else ""))
        for r in common.run_cycles(sc["path"], rtsv, rdir, [], sky=sc["sky"], threads=opt.threads,
                                   refs=[(ref_spp, k) for k in rseeds], keep=opt.keep_refs):
            r["dir"], r["rec"] = rdir, rr
            by_role.setdefault(r["role"], []).append(r)
    for r in runs:
        r["dir"] = cdir
        by_role.setdefault(r["role"], []).append(r)
    eq = by_role["equal_time"][0]
    refs = by_role["reference"]
    lum = [common.lum(x) for x in rec.rgb]
    lum2 = [common.lum(x) for x in rec2.rgb]
    def load(r):
        v = [common.lum(x) for x in common.read_f32_rgb(os.path.join(r["dir"], r["file"]))]
        return r["rec"].per_receiver(v) if "rec" in r else v
    r1, r2, ceq = load(refs[0]), load(refs[1]), load(eq)
    calib = [(r, load(r)) for r in by_role["calibration"]]
    est = float(rec.meta.get("est_rel_rmse", "nan"))
    ref_cpu = sum(r["cpu_s"] for r in refs)
    tags = sc.get("tags")
    out("")
    if tags:
        out("== %s [%s set] %s level %s, %s-lit, %s density (%g texels/m), %s charts" % (
            sc["name"], tags["set"], tags["family"], tags["level"], tags["lighting"], tags["density"],
            tags["texel_density"], tags["layout"]))
    out("== %s: lbk %.1f s wall, %.1f s CPU (%s spp, %s; estimated error %.1f %%); Cycles at equal %s time: "
        "%d spp, %.1f s CPU, %.1f s wall; reference 2 x %d spp%s (%.0f s CPU)" % (
            sc["name"], lbk_wall, lbk_cpu, rec.meta.get("spp", "?"), rec.meta.get("status", "?"), 100 * est,
            opt.clock.upper() if opt.clock == "cpu" else opt.clock, eq["spp"], eq["cpu_s"], eq["wall_s"], ref_spp,
            " per point at %.1f footprint points per texel%s" % (fp_points, " (jittered, own points per reference)"
                                                             if opt.jitter else " (stratum centres)")
            if fp_points > 1 else "", ref_cpu) + alt_txt)
    alt_head = "" if not opt.alt else " %9s %9s %8s" % ("alt err", "alt bias", "alt/Cyc")
    out("  %-22s %-8s %6s %9s %9s %9s %9s %9s %10s %6s %9s%s" % (
        "object", "rep", "n", "lbk err", "lbk bias", "lbk noise", "lbk est", "Cyc err", "lbk/Cyc", "goal", "ref noise",
        alt_head))
    rows = []

    def alt_group(idx):
        return Group(idx, alt_lum, alt_lum2, r1, r2, ceq) if alt_lum else None

    def alt_cols(ga, g):
        return "" if not ga else " %9s %9s %8.2f" % (pct(ga.lbk), "%+7.1f %%" % (100 * ga.lbk_bias),
                                                     ga.lbk / g.cyc if g.cyc > 0 else float("inf"))

    # each lightmapped object's own estimate (the report's "objects", baker library 1.9); an LLG
    # prop's own ("llg_objects", 1.11: its probes' noise and the fit's residual at its vertex
    # targets), else the report's LLG class estimate, not the texels' level-wide figure it took
    # before; the level-wide figure for objects without any (older bakers)
    obj_est = {o.get("name"): o.get("est_rel_rmse") for o in report.get("objects") or []}
    llg_est = {o.get("name"): o.get("est_rel_rmse") for o in report.get("llg_objects") or []}
    llg_class_est = (report.get("errors") or {}).get("llg")

    def row(label, rep, idx, e=None):
        e = est if e is None else e
        g, ga = Group(idx, lum, lum2, r1, r2, ceq), alt_group(idx)
        ratio = g.lbk / g.cyc if g.cyc > 0 else float("inf")
        out("  %-22s %-8s %6d %9s %9s %9s %9s %9s %10.2f %6s %9s%s" % (
            label[:22], rep, g.n, pct(g.lbk), "%+7.1f %%" % (100 * g.lbk_bias), pct(g.lbk_noise), pct(e),
            pct(g.cyc), ratio, "n/r" if g.unresolved else "yes" if ratio <= 0.5 else "no", pct(g.ref_noise),
            alt_cols(ga, g)))
        return g, ratio, ga

    visible = [i for i in range(len(rec)) if not rec.flags[i] & (common.HIDDEN | common.OFFPLANE)]
    for o in sorted(set(rec.obj)):
        idx = [i for i in visible if rec.obj[i] == o]
        if not idx:
            continue
        rep, name = rec.objects.get(o, ("?", "object%d" % o))
        oe = obj_est.get(name) if rep == "lightmap" else llg_est.get(name, llg_class_est) if rep == "llg" else None
        g, ratio, ga = row(name, rep, idx, oe)
        rows.append({"scene": sc["name"], "object": name, "rep": rep, "n": g.n, "lbk_err": g.lbk,
                     "lbk_bias": g.lbk_bias, "lbk_noise": g.lbk_noise, "lbk_est": est if oe is None else oe,
                     "lbk_est_level": est, "lbk_est_own": oe is not None, "cycles_err": g.cyc,
                     "ratio": ratio, "ref_noise": g.ref_noise, "mean_lux": g.mean, "unresolved": g.unresolved,
                     "lbk_err_rms": g.lbk_rms, "lbk_noise_rms": g.lbk_noise_rms})
        if tags:
            rows[-1].update({k: v for k, v in tags.items() if k != "thin_m"})
            rows[-1]["thin_m"] = tags["thin_m"].get(name)
            # bias of the receivers facing up and down (a slab lit from the wrong side: top too dark,
            # underside too bright), each relative to its own mean reference
            for side, sgn in (("up", 1), ("down", -1)):
                sub = [i for i in idx if sgn * rec.nrm[i][1] > 0.7]
                if len(sub) >= 4:
                    gs = Group(sub, lum, lum2, r1, r2, ceq)
                    rows[-1]["bias_" + side], rows[-1]["err_" + side] = gs.lbk_bias, gs.lbk
        if ga:
            rows[-1].update({"alt_err": ga.lbk, "alt_bias": ga.lbk_bias})
        mats = sorted(set(rec.mat[i] for i in idx))
        if len(mats) > 1:
            for m in mats:
                sub = [i for i in idx if rec.mat[i] == m]
                if len(sub) >= 16:
                    row("  . " + rec.materials.get(m, str(m)), "", sub)
    tex = [i for i in visible if rec.kind[i] == "T"]
    g = Group(tex, lum, lum2, r1, r2, ceq)
    ga = alt_group(tex)
    out(("  %-22s %-8s %6d %9s %9s %9s %9s %9s %10.2f %6s %9s%s" % ("all texels", "", g.n, pct(g.lbk), "%+7.1f %%" % (
        100 * g.lbk_bias), pct(g.lbk_noise), pct(est), pct(g.cyc), g.lbk / g.cyc if g.cyc > 0 else float("inf"), "",
        "", alt_cols(ga, g))).rstrip())
    # the estimate normalises by the RMS of the values (TRANSPORT.md); compare like with like
    within = 0.5 <= est / g.lbk_rms <= 2 if g.lbk_rms > 0 else False
    out("  estimate vs measured (all texels, RMSE/RMS as the estimate): estimated %.2f %%, measured error %.2f %% "
        "(est/measured %.2f: %s), measured noise (seed 1 vs 2) %.2f %% (est/noise %.2f)" % (
            100 * est, 100 * g.lbk_rms, est / g.lbk_rms if g.lbk_rms else float("nan"),
            "within 2x" if within else "NOT within 2x", 100 * g.lbk_noise_rms,
            est / g.lbk_noise_rms if g.lbk_noise_rms else float("nan")))
    # LLG objects: the report's LLG class estimate (noise and the fit's residual at its vertex
    # targets, bake/probes/PROBES.md) against the error measured at their vertices
    llg_within = None
    verts = [i for i in visible if rec.kind[i] == "V"]
    llg_est = (report.get("errors") or {}).get("llg")
    if verts and llg_est is not None:
        gv = Group(verts, lum, lum2, r1, r2, ceq)
        llg_within = 0.5 <= llg_est / gv.lbk_rms <= 2 if gv.lbk_rms > 0 else gv.unresolved
        out("  LLG estimate vs measured (all LLG vertices, RMSE/RMS): estimated %.2f %%, measured error %.2f %% (%s; "
            "reference noise %.2f %%)" % (100 * llg_est, 100 * gv.lbk_rms,
                                          "est/measured %.2f: %s" % (llg_est / gv.lbk_rms, "within 2x" if llg_within
                                                                     else "NOT within 2x") if gv.lbk_rms > 0
                                          else "not resolved from the reference's noise", 100 * gv.ref_noise))
    # what equal wall time would have given (modelled: Cycles' error ~ 1/sqrt(spp), time linear in spp)
    cal = by_role["calibration"]
    if len(cal) >= 2 and eq["spp"] > 0 and g.cyc > 0:
        xs, ys = [r["spp"] for r in cal], [r["wall_s"] for r in cal]
        b = (ys[-1] - ys[0]) / (xs[-1] - xs[0]) if xs[-1] != xs[0] else 0
        a = ys[0] - b * xs[0]
        spp_w = max(1.0, (lbk_wall - max(a, 0)) / b) if b > 0 else float("nan")
        cw = g.cyc * math.sqrt(eq["spp"] / spp_w)
        out("  at equal wall time instead (%.1f s; modelled from the calibration runs): Cycles %.0f spp, all-texel "
            "error %.1f %%, lbk/Cycles %.2f" % (lbk_wall, spp_w, 100 * cw, g.lbk / cw))
    out("  left out (invisible, no reference value): %d of %d receivers whose sensor point is enclosed by "
        "geometry, %d texels moved off their own surface by the push-out (texel_dump HIDDEN, OFFPLANE)" % (
            sum(1 for f in rec.flags if f & common.HIDDEN), len(rec),
            sum(1 for f in rec.flags if f & common.OFFPLANE and not f & common.HIDDEN)))
    cal_txt = ", ".join("%d spp %.1f %%" % (r["spp"], 100 * Group(tex, lum, lum2, r1, r2, v).cyc) for r, v in calib)
    out("  Cycles calibration runs (all texels): %s; scene done in %.0f s" % (cal_txt, time.perf_counter() - t_scene))
    return rows, {"scene": sc["name"], "tags": tags, "lbk_wall_s": lbk_wall, "lbk_cpu_s": lbk_cpu, "lbk_est": est,
                  "cycles_equal_spp": eq["spp"], "cycles_equal_cpu_s": eq["cpu_s"], "cycles_equal_wall_s": eq["wall_s"],
                  "ref_spp": ref_spp, "all_texels": {"lbk_err": g.lbk, "lbk_bias": g.lbk_bias, "cycles_err": g.cyc,
                                                     "lbk_err_rms": g.lbk_rms, "lbk_noise_rms": g.lbk_noise_rms,
                                                     "ref_noise": g.ref_noise}, "est_within_2x": within,
                  "llg_est_within_2x": llg_within,
                  "alt_all_texels": {"err": ga.lbk, "bias": ga.lbk_bias} if ga else None}


def main():
    ap = argparse.ArgumentParser(description="lbk vs Cycles at equal time")
    env = os.environ.get
    ap.add_argument("--lbk", default=env("LBK", "build/lbk"))
    ap.add_argument("--dump", default=env("LBK_TEXEL_DUMP", "build/bench/cycles/texel_dump"))
    ap.add_argument("--scenes", default=env("LBK_SCENES", "scenes"))
    ap.add_argument("--work", default=env("BENCH_CYCLES_WORK", "build/bench-cycles"))
    ap.add_argument("--clock", default=env("CYCLES_CLOCK", "cpu"), choices=("cpu", "wall"))
    ap.add_argument("--threads", type=int, default=int(env("BENCH_CYCLES_THREADS", "0")) or os.cpu_count())
    ap.add_argument("--only", default=env("BENCH_CYCLES_SCENES", ""))
    # the scenes of a bench/levels manifest instead of SCENES
    ap.add_argument("--levels", default=env("BENCH_CYCLES_LEVELS", ""))
    ap.add_argument("--results", default="", help="results JSON (default WORK/results.json)")
    ap.add_argument("--quick", action="store_true", default=env("LBK_BENCH_QUICK", "0") not in ("", "0"))
    ap.add_argument("--no-analytic", action="store_true")
    # K x K sensors over each texel's footprint (0: one sensor at the texel's sample point)
    ap.add_argument("--footprint", type=int, default=int(env("BENCH_CYCLES_FOOTPRINT", "2")))
    # footprint points uniform in their strata, a seed per reference (0: the strata's centres)
    ap.add_argument("--jitter", type=int, default=int(env("BENCH_CYCLES_JITTER", "0")))
    # a second baker measured against the same references (seed 1 only); it must share the layout
    ap.add_argument("--alt", default=env("LBK_ALT", ""))
    ap.add_argument("--alt-dump", default=env("LBK_ALT_DUMP", ""))
    ap.add_argument("--alt-name", default=env("LBK_ALT_NAME", ""))
    # reuse a reference whose inputs (scene and sensor files, sample counts, harness) are unchanged
    ap.add_argument("--keep-refs", action="store_true",
                    default=env("BENCH_CYCLES_KEEP_REFS", "0") not in ("", "0"))
    opt = ap.parse_args()
    opt.alt_dump = opt.alt_dump or opt.dump
    os.makedirs(opt.work, exist_ok=True)
    if not opt.alt:  # the default second baker: the same lbk without adaptive sampling
        opt.alt = os.path.join(opt.work, "lbk-adaptive-off.sh")
        with open(opt.alt, "w") as f:
            f.write('#!/bin/sh\nexec "%s" "$@" --adaptive off\n' % os.path.abspath(opt.lbk).replace('"', '\\"'))
        os.chmod(opt.alt, 0o755)
        opt.alt_name = opt.alt_name or "adaptive off"
    elif opt.alt == "none":
        opt.alt = ""
    opt.alt_name = opt.alt_name or "alt"
    t0 = time.perf_counter()
    lines = []

    def out(s):
        print(s, flush=True)
        lines.append(s)
    ver = subprocess.run([common.blender(), "--version"], capture_output=True, text=True).stdout.split("\n")[0]
    out("lbk vs Cycles (%s, CPU, %d threads each) at equal %s time; lbk: %s%s" % (
        ver, opt.threads, opt.clock, opt.lbk, "; alt = %s: %s" % (opt.alt_name, opt.alt) if opt.alt else ""))
    ok = True
    if not opt.no_analytic:
        ok = analytic.run(os.path.join(opt.work, "analytic"), opt.lbk, opt.dump, opt.threads, out,
                          alt=(opt.alt_name, opt.alt, opt.alt_dump) if opt.alt else None)
        if not ok:
            out("  ANALYTIC CHECK FAILED: Cycles' units or the sensor orientation are wrong; the comparison is void")
    only = [s for s in opt.only.split(",") if s]
    rows, scenes = [], []
    for sc in (levels_scenes(opt.levels) if opt.levels else SCENES):
        if (only and sc["name"] not in only) or (not only and sc.get("on_request")):
            continue
        r, s = run_scene(sc, opt.work, opt, out)
        rows += r
        scenes.append(s)
    out("")
    # a levels run: one line per set (dev, validation), never pooled (bench/levels/README.md)
    groups = [("", rows, scenes)] if not opt.levels else [
        ("[%s set] " % k, [r for r in rows if r["set"] == k], [s for s in scenes if s["tags"]["set"] == k])
        for k in ("dev", "validation") if any(s["tags"]["set"] == k for s in scenes)]
    for label, grows, gscenes in groups:
        resolved = [r for r in grows if not r["unresolved"]]
        met = sum(1 for r in resolved if r["ratio"] <= 0.5)
        out("%sgoal lbk error <= 0.5 x Cycles' at equal time: met on %d of %d objects (%d more not resolved: the "
            "reference's noise exceeds lbk's or Cycles' error, n/r); estimate within 2x of the measured error on %d of "
            "%d scenes" % (label, met, len(resolved), len(grows) - len(resolved),
                           sum(s["est_within_2x"] for s in gscenes), len(gscenes)))
    out("bench took %.0f s" % (time.perf_counter() - t0))
    with open(opt.results or os.path.join(opt.work, "results.json"), "w") as f:
        json.dump({"rows": rows, "scenes": scenes, "clock": opt.clock, "threads": opt.threads, "lbk": opt.lbk,
                   "blender": ver, "analytic_ok": ok}, f, indent=1)
    with open(opt.results[:-len(".json")] + ".report.txt" if opt.results.endswith(".json")
              else os.path.join(opt.work, "report.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
