#!/usr/bin/env python3
"""Distributed bakes of base-only levels with shared caches (bake/dist/DIST.md §Shared caches):
for N = 1, 2, 4, 8, 16 units, the units' total work against the local bake's, the critical path
(the longest chain of stages when every unit has its own machine), both as ratios to the local
bake measured in the same run, the bytes moved, and a projection to 64 and 256 machines.

Units run one after another here (a 2-core machine cannot show 16 at once; tests/e2e runs them
together, xargs -P and Slurm, byte-identical): the first computes every cache share, the others
read them, so each unit's CPU time splits into what it computed (the share files record their
seconds), what it published and read, and the rest (import, layout, its gather slice). The
critical path with one machine per unit is then
    max over units (rest) + sum over the cache's bounce stages (max over shares of its seconds)
    + the reads of one unit + 1/N of the publishing + the merge,
every bounce a barrier (each unit waits for the slowest share before the next bounce). Every
merge is checked byte-identical to the local bake. CPU seconds, --threads 1 everywhere; the
local bake without its path check, which only a local bake makes (a report, no container byte).

    python3 bench/scale/dist_shared.py --lbk build/lbk [--out DIR] [--levels cornell,city256]
                                       [--units 1,2,4,8,16]
"""
import argparse
import glob
import os
import re
import shutil
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(HERE, "..", "cycles"))
import common  # noqa: E402  (run_timed)
LEVELS = {
    "cornell": (os.path.join(ROOT, "scenes/cornell_box/CornellBox-Original.gltf"),
                "--samples 512 --target-error none --texel-density 8"),
    "cornell-target": (os.path.join(ROOT, "scenes/cornell_box/CornellBox-Original.gltf"), "--texel-density 8"),
    "city256": ("city:1/256", "--samples 256 --target-error none --texel-density 3.5"),
    "city256-1k": ("city:1/256", "--samples 1024 --target-error none --texel-density 3.5"),
    "city64": ("city:1/64", "--samples 256 --target-error none --texel-density 3.5"),
}
STATS = re.compile(r"unit (\d+): cache shares computed (\d+) \(([\d.]+) s\), read (\d+) \(([\d.]+) MB, ([\d.]+) s\), "
                   r"waited ([\d.]+) s, published ([\d.]+) s")


def cpu_of(cmd, log):
    """Runs cmd; its CPU seconds (user + system) and wall seconds."""
    wall, cpu = common.run_timed(cmd, log, "dist_shared")
    return cpu, wall


def scene_of(spec, out):
    if not spec.startswith("city:"):
        return spec
    frac = spec[5:]
    d = os.path.join(out, "city_" + frac.replace("/", "_"))
    os.makedirs(d, exist_ok=True)
    num, den = frac.split("/")
    subprocess.run([sys.executable, os.path.join(HERE, "gen_city.py"), "--out", d, "--fraction",
                    str(float(num) / float(den))], check=True, stdout=subprocess.DEVNULL)
    return os.path.join(d, "city.gltf")


def share_stages(cache_dir):
    """Per bounce stage (run, pass, half, bounce): the seconds of each of its shares, and bytes."""
    stages, total_bytes = {}, 0
    for path in glob.glob(os.path.join(cache_dir, "*.lbkcache")):
        with open(path, "rb") as f:
            h = f.read(144)
        total_bytes += os.path.getsize(path)
        run, pas, half, bounce = struct.unpack_from("<4I", h, 32)
        secs, = struct.unpack_from("<d", h, 112)
        stages.setdefault((run, pas, half, bounce), []).append(secs)
    return stages, total_bytes


def bench_level(opt, name):
    spec, opts = LEVELS[name]
    d = os.path.join(opt.out, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    scene = scene_of(spec, opt.out)
    base = [opt.lbk]
    extra = opts.split() + ["--threads", "1"]
    # the path check (a report of the bake's bias, no byte of the container) is a local bake's only
    local, _ = cpu_of(base + ["bake", scene, "-o", os.path.join(d, "local.lbk"), "-q", "--path-check", "off"] + extra,
                      os.path.join(d, "local.log"))
    print("\n%s: %s %s\nlocal lbk bake: %.2f CPU s (1 thread, --path-check off)" % (name, os.path.relpath(scene, ROOT) if scene.startswith(ROOT)
                                                                  else scene, opts, local))
    print("%5s %10s %7s %10s %9s %9s %9s %8s %10s %8s  %s" % ("units", "sum units", "/local", "critical", "/local",
                                                               "max rest", "stages", "reads", "MB moved", "merge", "bytes"))
    rows = {}
    for n in opt.units:
        plan = os.path.join(d, "p%d.json" % n)
        out = os.path.join(d, "m%d.lbk" % n)
        cache = os.path.join(d, "cache%d" % n)
        subprocess.run(base + ["plan", scene, "-o", out, "--plan", plan, "--units", str(n)] + opts.split(), check=True,
                       stdout=subprocess.DEVNULL)
        units = []
        for k in range(n):
            log = os.path.join(d, "u%d-%d.log" % (n, k))
            cpu, _ = cpu_of(base + ["bake-unit", plan, str(k), "-o", os.path.join(d, "part%d-%d.lbkpart" % (n, k)),
                                    "--threads", "1", "--cache-dir", cache], log)
            m = STATS.search(open(log).read())
            comp, read, pub = (float(m.group(3)), float(m.group(6)), float(m.group(8))) if m else (0.0, 0.0, 0.0)
            units.append({"cpu": cpu, "computed_s": comp, "read_s": read, "publish_s": pub,
                          "read_mb": float(m.group(5)) if m else 0.0})
        stages, share_bytes = share_stages(cache)
        parts = sorted(glob.glob(os.path.join(d, "part%d-*.lbkpart" % n)))
        merge, _ = cpu_of(base + ["merge", plan] + parts + ["-o", out, "-q", "--threads", "1", "--cache-dir", cache],
                          os.path.join(d, "merge%d.log" % n))
        if subprocess.run(["cmp", "-s", out, os.path.join(d, "local.lbk")]).returncode:
            sys.exit("dist_shared: the merge of %d units differs from the local bake" % n)
        total = sum(u["cpu"] for u in units) + merge
        # run one after another, the first unit computes and publishes every share; on N machines
        # each publishes its own 1/N of them
        rest = max(u["cpu"] - u["computed_s"] - u["read_s"] - u["publish_s"] for u in units)
        stage_path = sum(max(v) for v in stages.values())
        reads = max(u["read_s"] for u in units)
        publish = sum(u["publish_s"] for u in units) / n
        critical = rest + stage_path + reads + publish + merge if n > 1 else total
        moved = sum(u["read_mb"] for u in units) + share_bytes / 1e6
        rows[n] = {"total": total, "critical": critical, "rest": rest, "stage_path": stage_path, "publish": publish * n,
                   "stage_sum": sum(sum(v) for v in stages.values()), "stages": len(stages), "merge": merge,
                   "moved_mb": moved, "share_bytes": share_bytes}
        print("%5d %9.2fs %7.2f %9.2fs %9.3f %8.2fs %8.2fs %7.2fs %10.1f %7.2fs  %d stages, parts %d B" % (
            n, total, total / local, critical, critical / local, rest, stage_path, reads, moved, merge, len(stages),
            sum(os.path.getsize(p) for p in parts)))
        for p in parts:
            os.remove(p)
    project(local, rows)
    return rows


def project(local, rows):
    """Wall time on M machines from the two largest measured N: a unit's rest = setup + gather/N,
    the bounce stages' work divided by M plus a per-stage latency, reads of every share."""
    ns = sorted(n for n in rows if n > 1)
    if len(ns) < 2:
        return
    a, b = ns[-2], ns[-1]
    ga = (rows[a]["rest"] - rows[b]["rest"]) / (1.0 / a - 1.0 / b) if a != b else 0
    ga = max(ga, 0.0)
    setup = max(rows[b]["rest"] - ga / b, 0.0)
    r = rows[b]
    latency = 0.005  # per bounce stage: a file system round trip to see the last share appear
    bandwidth = 1e9  # bytes per second into one unit (10 GbE)
    print("  fit from N = %d, %d: per unit %.2f s of import/layout + %.2f s of gather / N; the cache's %d stages "
          "%.2f s of work; each unit reads %.1f MB" % (a, b, setup, ga, r["stages"], r["stage_sum"], r["share_bytes"] / 1e6))
    for m in (64, 256):
        t = (setup + ga / m + r["stage_sum"] / m + r["stages"] * latency + r["share_bytes"] / bandwidth + r["publish"] / m
             + r["merge"])
        print("  projected on %d machines: %.2f s = %.3f x the local bake (%.1f x faster), assuming %.0f ms per stage "
              "and %.0f GB/s per unit" % (m, t, t / local, local / t, latency * 1e3, bandwidth / 1e9))


def main():
    ap = argparse.ArgumentParser(description="distributed bakes of base-only levels with shared caches")
    ap.add_argument("--lbk", required=True)
    ap.add_argument("--out", default="/tmp/lbk-dist-shared")
    ap.add_argument("--levels", default="cornell,city256")
    ap.add_argument("--units", default="1,2,4,8,16")
    opt = ap.parse_args()
    opt.lbk = os.path.abspath(opt.lbk)
    opt.units = [int(x) for x in opt.units.split(",")]
    os.makedirs(opt.out, exist_ok=True)
    print("Distributed bakes with shared caches (CPU seconds, 1 thread per process; ratios to the local bake)")
    for name in opt.levels.split(","):
        if name not in LEVELS:
            sys.exit("dist_shared: unknown level %s (%s)" % (name, ", ".join(LEVELS)))
        bench_level(opt, name)


if __name__ == "__main__":
    main()
