"""Proofs of units and orientation: scenes with a closed-form irradiance, baked by Cycles through
the same path as the benchmark scenes (glTF -> gltf_scene.py -> sensors -> cycles_bake.py), and
by lbk (texel_dump), each compared with the formula.

  sky       uniform sky of radiance L = (0.5, 1, 2) over a 1 km plane of albedo 0.5:
            up-facing E = pi L; horizontal E = pi L (1 + rho) / 2; down-facing E = pi rho L
  point     I = 10 cd at height 2 over a black plane: E = I h / d^3 (d = distance to the light)
  sun       directional light of 3 lux: E = 3 max(0, -n . d) for random normals n
  emitter   a 2 x 2 m double-sided emissive square (emissiveFactor (0.25, 0.5, 1) x
            emissiveStrength 4: L = (1, 2, 4) nits) 1.5 m above a black floor: E = pi L F below
            and above it, F the form factor of a rectangle seen from a point (corner decomposition)
  spot      I = 20 cd spot pointing down from 3 m (cones 0.4 / 0.6 rad), receivers inside the
            inner cone and in the edge: E = I t^2 cos / d^2, t the glTF/lbk cone blend
  furnace   inside a closed box whose walls (albedo 0.8) all emit 0.5 nits: E = pi Le / (1 - rho)
            everywhere (all bounces: Cycles' bounce limit and Russian roulette are unbiased here)

Orientation: the point, sun and emitter receivers all have different irradiance and no
symmetry lines up with the image grid, so reading the bake image with its rows in the other
order gives a large error; both readings are printed.
"""
import math
import os

import common
import gltf_write


def rng(seed):
    x = seed
    while True:
        x = (x * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        yield (x >> 11) / float(1 << 53)


def plane(w, y, half, mat, up=True):
    h = half
    if up:
        return gltf_write.quad((-h, y, h), (h, y, h), (h, y, -h), (-h, y, -h)), mat
    return gltf_write.quad((-h, y, -h), (h, y, -h), (h, y, h), (-h, y, h)), mat


def add_plane(w, name, y, half, mat, up=True):
    (pos, nrm, idx), m = plane(w, y, half, mat, up)
    w.mesh(name, [{"pos": pos, "nrm": nrm, "idx": idx, "material": m}])


def rect_form_factor(px, pz, h, x0, x1, z0, z1):
    """Form factor from an up-facing point to a parallel rectangle h above it."""
    def corner(x, y):
        if x == 0 or y == 0:
            return 0.0
        X, Y = abs(x) / h, abs(y) / h
        f = (X / math.sqrt(1 + X * X) * math.atan(Y / math.sqrt(1 + X * X)) +
             Y / math.sqrt(1 + Y * Y) * math.atan(X / math.sqrt(1 + Y * Y))) / (2 * math.pi)
        return math.copysign(1, x) * math.copysign(1, y) * f
    a0, a1, b0, b1 = x0 - px, x1 - px, z0 - pz, z1 - pz
    return corner(a1, b1) - corner(a0, b1) - corner(a1, b0) + corner(a0, b0)


def scene_sky(d):
    w = gltf_write.Writer()
    add_plane(w, "ground", 0.0, 500.0, w.material("ground", base=(0.5, 0.5, 0.5)))
    path = os.path.join(d, "sky.gltf")
    w.save(path)
    L, rho = (0.5, 1.0, 2.0), 0.5
    r = rng(1)
    pos, nrm, groups = [], [], []
    for i in range(96):
        x, z = 20 * next(r) - 10, 20 * next(r) - 10
        g = i % 3
        n = [(0, 1, 0), (1, 0, 0), (0, -1, 0)][g]
        pos.append((x, 1.0 if g else 0.0, z))
        nrm.append(n)
        groups.append(["up", "horizontal", "down"][g])

    def formula(p, n):
        f = [1.0, (1 + rho) / 2, rho][0 if n[1] > 0.5 else 2 if n[1] < -0.5 else 1]
        return tuple(math.pi * l * f for l in L)
    return {"name": "sky", "gltf": path, "sky": L, "pos": pos, "nrm": nrm, "groups": groups, "formula": formula,
            "spp": 1024, "lbk_args": ["--sky", "0.5,1,2", "--texel-density", "0.02"], "lbk_select": lambda p, n: True}


def scene_point(d):
    w = gltf_write.Writer()
    add_plane(w, "ground", 0.0, 4.0, w.material("black", base=(0, 0, 0)))
    L = (0.7, 2.0, 0.3)
    I = 10.0
    w.light("lamp", "point", I, translation=L)
    path = os.path.join(d, "point.gltf")
    w.save(path)
    r = rng(2)
    pos = [(6 * next(r) - 3, 0.0, 6 * next(r) - 3) for _ in range(200)]
    nrm = [(0, 1, 0)] * len(pos)

    def formula(p, n):
        v = [L[k] - p[k] for k in range(3)]
        dd = math.sqrt(sum(x * x for x in v))
        c = max(0.0, sum(v[k] * n[k] for k in range(3)) / dd)
        return (I * c / (dd * dd),) * 3
    return {"name": "point", "gltf": path, "sky": (0, 0, 0), "pos": pos, "nrm": nrm, "groups": ["all"] * len(pos),
            "formula": formula, "spp": 16, "lbk_args": [], "lbk_select": lambda p, n: n[1] > 0.5}


def scene_sun(d):
    w = gltf_write.Writer()
    add_plane(w, "ground", 0.0, 4.0, w.material("black", base=(0, 0, 0)))
    dirn = (-0.3, -1.0, -0.5)
    ln = math.sqrt(sum(x * x for x in dirn))
    dirn = tuple(x / ln for x in dirn)
    # glTF lights shine along their node's -Z: rotate -Z onto dirn (quaternion x, y, z, w)
    a = (0.0, 0.0, -1.0)
    ax = (a[1] * dirn[2] - a[2] * dirn[1], a[2] * dirn[0] - a[0] * dirn[2], a[0] * dirn[1] - a[1] * dirn[0])
    c = sum(a[k] * dirn[k] for k in range(3))
    q = (ax[0], ax[1], ax[2], 1 + c)
    qn = math.sqrt(sum(x * x for x in q))
    E = 3.0
    w.light("sun", "directional", E, rotation=tuple(x / qn for x in q))
    path = os.path.join(d, "sun.gltf")
    w.save(path)
    r = rng(3)
    pos, nrm = [], []
    for _ in range(200):
        pos.append((6 * next(r) - 3, 0.5 + 1.5 * next(r), 6 * next(r) - 3))
        zz = 2 * next(r) - 1
        ph = 2 * math.pi * next(r)
        s = math.sqrt(1 - zz * zz)
        nrm.append((s * math.cos(ph), zz, s * math.sin(ph)))

    def formula(p, n):
        return (E * max(0.0, -sum(n[k] * dirn[k] for k in range(3))),) * 3
    return {"name": "sun", "gltf": path, "sky": (0, 0, 0), "pos": pos, "nrm": nrm, "groups": ["all"] * len(pos),
            "formula": formula, "spp": 16, "lbk_args": [], "lbk_select": lambda p, n: n[1] > 0.5}


def scene_emitter(d):
    w = gltf_write.Writer()
    add_plane(w, "floor", 0.0, 4.0, w.material("black", base=(0, 0, 0)))
    H = 1.5
    # double-sided: it emits downwards and upwards (lbk and Cycles alike)
    add_plane(w, "emitter", H, 1.0, w.material("emitter", base=(0, 0, 0), emission=(0.25, 0.5, 1.0), strength=4.0,
                                               double_sided=True), up=False)
    path = os.path.join(d, "emitter.gltf")
    w.save(path)
    L = (1.0, 2.0, 4.0)
    r = rng(4)
    pos, nrm, groups = [], [], []
    for i in range(300):
        x, z = 4 * next(r) - 2, 4 * next(r) - 2
        if i % 3:
            pos.append((x, 1.2 * next(r), z))
            nrm.append((0, 1, 0))
            groups.append("below")
        else:
            pos.append((x, H + 0.3 + next(r), z))
            nrm.append((0, -1, 0))
            groups.append("above (back)")

    def formula(p, n):
        f = rect_form_factor(p[0], p[2], abs(H - p[1]), -1, 1, -1, 1)
        return tuple(math.pi * l * f for l in L)
    return {"name": "emitter", "gltf": path, "sky": (0, 0, 0), "pos": pos, "nrm": nrm, "groups": groups,
            "formula": formula, "spp": 1024, "lbk_args": ["--texel-density", "4"],
            "lbk_select": lambda p, n: n[1] > 0.5 and p[1] < 0.5}


def scene_spot(d):
    w = gltf_write.Writer()
    add_plane(w, "ground", 0.0, 4.0, w.material("black", base=(0, 0, 0)))
    L = (0.3, 3.0, -0.2)
    I, inner, outer = 20.0, 0.4, 0.6
    # pointing straight down: -Z onto -Y is a -90 degree rotation about X
    s = math.sqrt(0.5)
    w.light("spot", "spot", I, translation=L, rotation=(-s, 0, 0, s),
            spot={"innerConeAngle": inner, "outerConeAngle": outer})
    path = os.path.join(d, "spot.gltf")
    w.save(path)
    r = rng(5)
    pos, groups = [], []
    while len(pos) < 300:
        p = (L[0] + 4.4 * next(r) - 2.2, 0.0, L[2] + 4.4 * next(r) - 2.2)
        ang = math.atan2(math.hypot(p[0] - L[0], p[2] - L[2]), L[1])
        if ang < inner - 0.02 and groups.count("inner cone") < 150:
            pos.append(p)
            groups.append("inner cone")
        elif inner + 0.02 < ang < outer - 0.02 and groups.count("cone edge") < 150:
            pos.append(p)
            groups.append("cone edge")
    nrm = [(0, 1, 0)] * len(pos)

    def formula(p, n):
        v = [L[k] - p[k] for k in range(3)]
        dd = math.sqrt(sum(x * x for x in v))
        ang = math.acos(max(-1.0, min(1.0, v[1] / dd)))
        t = min(1.0, max(0.0, (math.cos(ang) - math.cos(outer)) / (math.cos(inner) - math.cos(outer))))
        return (I * t * t * v[1] / dd / (dd * dd),) * 3

    def inside(p, n):
        return n[1] > 0.5 and math.atan2(math.hypot(p[0] - L[0], p[2] - L[2]), L[1]) < outer - 0.02
    return {"name": "spot", "gltf": path, "sky": (0, 0, 0), "pos": pos, "nrm": nrm, "groups": groups,
            "formula": formula, "spp": 16, "lbk_args": [], "lbk_select": inside}


def scene_furnace(d):
    w = gltf_write.Writer()
    rho, le = 0.8, 0.5
    m = w.material("furnace", base=(rho, rho, rho), emission=(le, le, le))
    a = 1.0
    faces = [  # counter-clockwise seen from outside; reversed below to face inwards
        ((-a, -a, -a), (a, -a, -a), (a, -a, a), (-a, -a, a)),
        ((-a, a, -a), (-a, a, a), (a, a, a), (a, a, -a)),
        ((-a, -a, -a), (-a, a, -a), (a, a, -a), (a, -a, -a)),
        ((-a, -a, a), (a, -a, a), (a, a, a), (-a, a, a)),
        ((-a, -a, -a), (-a, -a, a), (-a, a, a), (-a, a, -a)),
        ((a, -a, -a), (a, a, -a), (a, a, a), (a, -a, a))]
    pos, nrm, idx = gltf_write.merge([gltf_write.quad(*reversed(f)) for f in faces])
    # every triangle emits: lbk would leave it unlit (classify.h rule 2) unless told otherwise
    w.mesh("box", [{"pos": pos, "nrm": nrm, "idx": idx, "material": m}], extras={"lbk_lighting": "lightmap"})
    path = os.path.join(d, "furnace.gltf")
    w.save(path)
    r = rng(6)
    pos, nrm = [], []
    for _ in range(100):
        pos.append(tuple(1.6 * next(r) - 0.8 for _ in range(3)))
        zz = 2 * next(r) - 1
        ph = 2 * math.pi * next(r)
        s = math.sqrt(1 - zz * zz)
        nrm.append((s * math.cos(ph), zz, s * math.sin(ph)))

    def formula(p, n):
        return (math.pi * le / (1 - rho),) * 3
    return {"name": "furnace", "gltf": path, "sky": (0, 0, 0), "pos": pos, "nrm": nrm, "groups": ["all"] * len(pos),
            "formula": formula, "spp": 256, "lbk_args": [], "lbk_select": lambda p, n: True}


SCENES = [scene_sky, scene_point, scene_sun, scene_emitter, scene_spot, scene_furnace]


def ratio_stats(got, want):
    """Mean of got/want (luminance) and the relative RMS deviation sqrt(mean((got-want)^2))/mean(want)."""
    n = len(want)
    num = sum((common.lum(g) - common.lum(w)) ** 2 for g, w in zip(got, want))
    den = sum(common.lum(w) for w in want) / n
    ratio = sum(common.lum(g) for g in got) / max(1e-30, sum(common.lum(w) for w in want))
    return ratio, math.sqrt(num / n) / den if den > 0 else float("nan")


def channel_ratios(got, want):
    return [sum(g[c] for g in got) / max(1e-30, sum(w[c] for w in want)) for c in range(3)]


def lbk_vs_formula(sc, work, lbk, dump, threads, tag):
    """lbk on the same scene: its own texels, the formula evaluated at each -> (ratio, rms, n)."""
    name = sc["name"]
    lbk_file = os.path.join(work, name + tag + ".lbk")
    common.run_timed([lbk, "bake", sc["gltf"], "-o", lbk_file, "--threads", str(threads or 0)] + sc["lbk_args"],
                     os.path.join(work, name + tag + ".lbk.log"))
    ltsv = os.path.join(work, name + tag + ".lbk.tsv")
    dargs = [a for a in sc["lbk_args"] if a != "--sky"]
    dargs = dargs[dargs.index("--texel-density"):] if "--texel-density" in dargs else []
    common.run_timed([dump, sc["gltf"], lbk_file, ltsv] + dargs, os.path.join(work, name + tag + ".dump.log"))
    rec = common.Receivers(ltsv)
    sel = [i for i in range(len(rec)) if sc["lbk_select"](rec.pos[i], rec.nrm[i])]
    lw = [sc["formula"](rec.pos[i], rec.nrm[i]) for i in sel]
    lg = [rec.rgb[i] for i in sel]
    lratio, lrms = ratio_stats(lg, lw)
    return lratio, lrms, len(sel)


def run(work, lbk, dump, threads, out=print, alt=None):
    """Prints the table; returns whether Cycles passed every check (lbk's columns are findings
    about lbk, not checks of the harness). alt: (name, lbk, dump) of a second baker whose own
    texels get the same columns."""
    os.makedirs(work, exist_ok=True)
    ok = True
    out("unit and orientation proofs (Cycles and lbk against closed-form irradiance):")
    out("  %-8s %-11s %5s %9s %9s %9s  %-22s %9s %9s %6s%s" % (
        "scene", "receivers", "n", "Cyc/true", "Cyc rms", "flipped", "Cyc R/G/B ratio", "lbk/true", "lbk rms", "texels",
        "" if not alt else " %9s %9s" % ("alt/true", "alt rms")))
    for make in SCENES:
        sc = make(work)
        name = sc["name"]
        want = [sc["formula"](p, n) for p, n in zip(sc["pos"], sc["nrm"])]
        tsv = os.path.join(work, name + ".tsv")
        common.write_receivers(tsv, sc["pos"], sc["nrm"], want)
        cdir = os.path.join(work, name + ".cycles")
        runs = common.run_cycles(sc["gltf"], tsv, cdir, [(sc["spp"], 1)], sky=sc["sky"], threads=threads)
        got = common.read_f32_rgb(os.path.join(cdir, runs[0]["file"]))
        flipped = common.read_f32_rgb(os.path.join(cdir, "flipped_" + runs[0]["file"]))
        lratio, lrms, nsel = lbk_vs_formula(sc, work, lbk, dump, threads, "")
        if alt:
            aratio, arms, _ = lbk_vs_formula(sc, work, alt[1], alt[2], threads, ".alt")
        for gi, g in enumerate(sorted(set(sc["groups"]))):
            idx = [i for i, x in enumerate(sc["groups"]) if x == g]
            r, rms = ratio_stats([got[i] for i in idx], [want[i] for i in idx])
            _, frms = ratio_stats([flipped[i] for i in idx], [want[i] for i in idx])
            ch = channel_ratios([got[i] for i in idx], [want[i] for i in idx])
            lbk_cols = "%9.4f %8.2f%% %6d" % (lratio, 100 * lrms, nsel) if gi == 0 else ""
            if alt and gi == 0:
                lbk_cols += " %9.4f %8.2f%%" % (aratio, 100 * arms)
            out("  %-8s %-11s %5d %9.4f %8.2f%% %8.1f%%  %-22s %s" % (
                name, g, len(idx), r, 100 * rms, 100 * frms, "/".join("%.3f" % x for x in ch), lbk_cols))
            # the proof: Cycles within 2 % of the formula (its noise is below 0.3 % except in the
            # furnace), and far off when the image rows are read the other way round
            ok &= abs(r - 1) < 0.02 and all(abs(x - 1) < 0.03 for x in ch) and (frms > 0.2 or name == "furnace")
    out("  Cyc/true: mean Cycles / formula (luminance); rms: RMS deviation / mean; flipped: the same, reading the "
        "bake image's rows in the other order; lbk: its own texels on the receiving surfaces")
    return ok


if __name__ == "__main__":
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", default="build/bench-cycles/analytic")
    ap.add_argument("--lbk", default=os.environ.get("LBK", "build/lbk"))
    ap.add_argument("--dump", default=os.environ.get("LBK_TEXEL_DUMP", "build/bench/cycles/texel_dump"))
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    raise SystemExit(0 if run(a.work, a.lbk, a.dump, a.threads) else 1)
