#!/usr/bin/env python3
"""make bench-suite / the levels part of make bench: writes the hard levels (gen_levels.py),
measures lbk against Cycles on each with bench/cycles/run.py (--levels: the same harness as
make bench-cycles, equal CPU time), then prints the summary (summary.py), per set.

    python3 bench/levels/suite.py [--subset] [--quick] [--set dev|validation|all] [--levels L1,L2,...]

--subset: make bench's few dev scenes (QUICK_SCENES), no analytic check (bench-cycles runs it).
Environment (or the options): LBK, LBK_TEXEL_DUMP (as bench-cycles), BENCH_LEVELS_WORK (scratch,
default build/bench-levels), BENCH_LEVELS_SET (default all; dev with --subset), BENCH_LEVELS (a
subset of levels), LBK_BENCH_QUICK=1 / --quick (short references: the manifest's ref_spp_quick).
BENCH_CYCLES_* variables reach run.py unchanged; LBK_ALT defaults to none (one baker).
"""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# make bench's subset: dev levels only (never validation), one thin-slab table with both layouts
# (1 cm top, sky through a window wall, 8 texels/m), the 7 cm round table of the level,
# and a 2 cm wall between a lit and a dark room.
QUICK = ["table_slab_00", "table_slab_01", "thin_wall_00"]
QUICK_SCENES = ["table_slab_00", "table_slab_00_authored", "table_slab_01", "thin_wall_00"]


def main():
    env = os.environ.get
    ap = argparse.ArgumentParser(description="lbk vs Cycles over the hard-level suite")
    ap.add_argument("--lbk", default=env("LBK", "build/lbk"))
    ap.add_argument("--dump", default=env("LBK_TEXEL_DUMP", "build/bench/cycles/texel_dump"))
    ap.add_argument("--work", default=env("BENCH_LEVELS_WORK", "build/bench-levels"))
    ap.add_argument("--set", default=env("BENCH_LEVELS_SET", ""), choices=("", "dev", "validation", "all"))
    ap.add_argument("--levels", default=env("BENCH_LEVELS", ""))
    ap.add_argument("--seed-base", default="1000")
    ap.add_argument("--quick", action="store_true", default=env("LBK_BENCH_QUICK", "0") not in ("", "0"))
    ap.add_argument("--subset", action="store_true")
    opt = ap.parse_args()
    lset = opt.set or ("dev" if opt.subset else "all")
    levels = opt.levels or (",".join(QUICK) if opt.subset else "")
    ldir = os.path.join(opt.work, "levels-" + lset)
    gen = [sys.executable, os.path.join(HERE, "gen_levels.py"), "--out", ldir, "--set", lset,
           "--seed-base", opt.seed_base]
    if levels:
        gen += ["--only", levels]
    subprocess.run(gen, check=True)
    results = os.path.join(opt.work, "results-%s%s%s.json" % (lset, "-subset" if opt.subset else "",
                                                              "-quick" if opt.quick else ""))
    run = [sys.executable, os.path.join(HERE, "..", "cycles", "run.py"), "--lbk", opt.lbk, "--dump", opt.dump,
           "--work", opt.work, "--levels", os.path.join(ldir, "manifest.json"), "--results", results,
           "--alt", env("LBK_ALT", "none")]
    if opt.quick:
        run.append("--quick")
    if opt.subset:
        run.append("--no-analytic")
        if not opt.levels:
            run += ["--only", ",".join(QUICK_SCENES)]
    st = subprocess.run(run).returncode
    if os.path.exists(results):
        subprocess.run([sys.executable, os.path.join(HERE, "summary.py"), results, "--out",
                        results[:-len(".json")] + ".summary.txt"], check=True)
    return st


if __name__ == "__main__":
    sys.exit(main())
