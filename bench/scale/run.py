#!/usr/bin/env python3
"""The scale bench (bench/scale/README.md): the generated city (gen_city.py) at growing fractions,
each baked at the fast preset, printing per fraction the time of every phase, the peak RSS and
bytes per texel, texels and probes per CPU second, and how the cost grows against the smallest
fraction measured in the same run (ratios, not absolute times: the machines are shared).

    python3 bench/scale/run.py --lbk build/lbk [--out DIR] [--fractions 1/64,1/16,1/4,1]
                               [--density 3.5] [--threads N] [--extra "ARGS"]
"""
import argparse
import json
import os
import resource
import shlex
import subprocess
import sys
import time
from fractions import Fraction

HERE = os.path.dirname(os.path.abspath(__file__))
GOAL_BYTES_PER_TEXEL = 120  # issue 36: peak RSS <= 120 B/texel + the scene and BVH


def run_one(opt, frac):
    d = os.path.join(opt.out, "f%s" % str(frac).replace("/", "_"))
    os.makedirs(d, exist_ok=True)
    subprocess.run([sys.executable, os.path.join(HERE, "gen_city.py"), "--out", d, "--fraction", str(float(frac)),
                    "--seed", str(opt.seed)], check=True, stdout=subprocess.DEVNULL)
    info = json.load(open(os.path.join(d, "city.json")))
    rep = os.path.join(d, "report.json")
    cmd = [opt.lbk, "bake", os.path.join(d, "city.gltf"), "-o", os.path.join(d, "city.lbk"), "--texel-density",
           str(opt.density), "--texel-budget", str(opt.texel_budget), "--json-report", rep]
    if opt.threads:
        cmd += ["--threads", str(opt.threads)]
    cmd += shlex.split(opt.extra)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(os.path.join(d, "bake.log"), "w") as log:
        r = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode:
        sys.exit("bench-scale: %s failed (exit %d); see %s" % (" ".join(cmd), r.returncode, os.path.join(d, "bake.log")))
    j = json.load(open(rep))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    c = j["counts"]
    phases = {p["name"]: p for p in j["phases"]}
    peak = max(p["peak_rss_bytes"] for p in j["phases"])
    samples = j["samples"][-1]["samples_per_receiver"] if j["samples"] else 0
    return {"fraction": str(frac), "triangles": info["triangles"], "texels": c["texels"], "pages": c["pages"],
            "glg_probes": c["glg_probes"], "wall_s": wall, "cpu_s": cpu, "peak_rss": peak,
            "phase_s": {k: v["seconds"] for k, v in phases.items()},
            "phase_peak": {k: v["peak_rss_bytes"] for k, v in phases.items()},
            "samples": samples, "rays": j["transport"]["rays"], "transport_s": j["transport"]["seconds"],
            "file_bytes": c["file_bytes"]}


def main():
    ap = argparse.ArgumentParser(description="lbk's scale bench on the generated city")
    ap.add_argument("--lbk", required=True)
    ap.add_argument("--out", default="build/bench-scale")
    ap.add_argument("--fractions", default="1/64,1/16,1/4,1")
    ap.add_argument("--density", type=float, default=3.5, help="texels per metre (3.5: ~50 M texels for the city)")
    ap.add_argument("--texel-budget", type=int, default=1 << 27)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--extra", default="", help="more lbk bake arguments")
    opt = ap.parse_args()
    fracs = [Fraction(x) for x in opt.fractions.split(",") if x]
    if not fracs or any(not (0 < f <= 1) for f in fracs):
        sys.exit("bench-scale: --fractions takes fractions in (0, 1], e.g. 1/64,1/16")
    os.makedirs(opt.out, exist_ok=True)
    rows = []
    print("bench-scale: the city (bench/scale/gen_city.py, seed %d) at %g texels/m, fast preset" % (opt.seed, opt.density))
    print("%-6s %9s %10s %5s %8s %8s %8s %8s %8s %8s %8s %8s %9s %11s %11s" % (
        "part", "tris", "texels", "pages", "probes", "import", "layout", "light", "write", "wall s", "CPU s",
        "peak MB", "B/texel", "texel/CPUs", "probe/CPUs"))
    for f in fracs:
        r = run_one(opt, f)
        rows.append(r)
        p = r["phase_s"]
        print("%-6s %9d %10d %5d %8d %8.1f %8.1f %8.1f %8.1f %8.1f %8.1f %8.0f %9.0f %11.0f %11.0f" % (
            r["fraction"], r["triangles"], r["texels"], r["pages"], r["glg_probes"], p.get("import", 0),
            p.get("layout", 0), p.get("light", 0), p.get("write", 0), r["wall_s"], r["cpu_s"], r["peak_rss"] / 2**20,
            r["peak_rss"] / max(r["texels"], 1), r["texels"] * r["samples"] / max(r["cpu_s"], 1e-9),
            r["glg_probes"] / max(r["cpu_s"], 1e-9)))
        sys.stdout.flush()
    base = rows[0]
    print("\ngrowth against the %s part, measured in this run (1.00: linear). The stop rule picks the"
          % base["fraction"])
    print("samples (a part with darker rooms runs more passes), so the transport's cost is compared per ray:")
    print("%-6s %9s %8s %8s %10s %10s %13s %14s %14s" % ("part", "texels x", "CPU x", "samples", "rays/texel",
                                                         "rays x", "transport/ray", "CPU per texel", "peak per texel"))
    for r in rows:
        tx = r["texels"] / max(base["texels"], 1)
        cx = r["cpu_s"] / max(base["cpu_s"], 1e-9)
        per_ray = (r["transport_s"] / max(r["rays"], 1)) / (base["transport_s"] / max(base["rays"], 1))
        print("%-6s %9.2f %8.2f %8d %10.0f %10.2f %13.2f %14.2f %14.2f" % (
            r["fraction"], tx, cx, r["samples"], r["rays"] / max(r["texels"], 1), r["rays"] / max(base["rays"], 1),
            per_ray, cx / tx if tx else 0, (r["peak_rss"] / max(r["texels"], 1)) / (base["peak_rss"] / max(base["texels"], 1))))
    last = rows[-1]
    bpt = last["peak_rss"] / max(last["texels"], 1)
    print("\nmemory goal (issue 36): %.0f B/texel peak at %s of the city against %d + the scene and BVH: %s" % (
        bpt, last["fraction"], GOAL_BYTES_PER_TEXEL, "met" if bpt <= GOAL_BYTES_PER_TEXEL else "NOT met"))
    with open(os.path.join(opt.out, "scale.json"), "w") as fo:
        json.dump({"density": opt.density, "seed": opt.seed, "rows": rows}, fo, indent=1, sort_keys=True)
        fo.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
