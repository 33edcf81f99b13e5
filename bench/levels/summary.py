#!/usr/bin/env python3
"""The suite's summary (README.md, "What the summary means") from bench/cycles/run.py's
results JSON of a levels run, per set (dev, validation; never pooled):

  lbk/Cycles over objects: lbk's relative RMSE over Cycles' at equal CPU time; median, 90th
    percentile, how many meet the goal (<= 0.5) and how many lose (> 1), and the worst five
    with their likely cause;
  estimate/measured over objects: lbk's own estimate (one per bake, REPT) over the object's
    measured error normalised like the estimate (RMSE / RMS); median, 10th and 90th percentile,
    and the five furthest from 1 (below 1: the bake claims less error than it has).

Objects whose difference is mostly the reference's own noise (n/r) are counted, not used.

    python3 bench/levels/summary.py RESULTS.json [--out SUMMARY.txt]
"""
import argparse
import json
import math
import sys


def quantile(xs, q):
    """Linear interpolation between order statistics (numpy's default)."""
    xs = sorted(xs)
    if not xs:
        return float("nan")
    k = (len(xs) - 1) * q
    i = int(math.floor(k))
    j = min(i + 1, len(xs) - 1)
    return xs[i] + (xs[j] - xs[i]) * (k - i)


def likely_cause(r):
    """A one-line guess at why an object's error is what it is, from its own numbers and tags."""
    why = []
    thin, dens = r.get("thin_m"), r.get("texel_density")
    if thin is not None and dens and thin * dens < 1.0:
        why.append("thin: %.3g cm = %.2f texel" % (100 * thin, thin * dens))
    err, bias, noise = r["lbk_err"], r["lbk_bias"], r["lbk_noise"]
    up, down = r.get("bias_up"), r.get("bias_down")
    if up is not None and down is not None and up < -0.05 and down > 0.05:
        why.append("lit from the wrong side: top %+.0f %%, underside %+.0f %%" % (100 * up, 100 * down))
    # where the error is: its top, its underside (bias_/err_up, _down: receivers facing up, down), or
    # neither (then its sides: a slab's edges, a wall's faces)
    faces = [(r["err_" + k], k, r["bias_" + k]) for k in ("up", "down") if r.get("err_" + k) is not None]
    if faces and err > 0:
        e, k, b = max(faces)
        if e > 1.5 * err:
            why.append("%s error %.0f %% (bias %+.0f %%)" % ("top" if k == "up" else "underside", 100 * e, 100 * b))
        elif len(faces) == 2 and e < 0.5 * err:
            why.append("the error is on its sides (top %.1f %%, underside %.1f %%)" % (
                100 * r["err_up"], 100 * r["err_down"]))
    if err > 0 and abs(bias) >= 0.5 * err:
        why.append("bias %+.1f %% (%s)" % (100 * bias, "too bright: leak?" if bias > 0 else "too dark: occluded?"))
    if err > 0 and noise >= 0.5 * err:
        why.append("noise %.1f %% (sample limit)" % (100 * noise))
    if r["n"] < 32:
        why.append("%d receivers" % r["n"])
    if r.get("layout") == "authored":
        why.append("authored charts")
    return "; ".join(why) or "error without dominant bias or noise (spread)"


def _est_ratio(r):
    m = r.get("lbk_err_rms")
    return r["lbk_est"] / m if m and m > 0 and r["lbk_est"] == r["lbk_est"] else float("nan")


def summarise(res, out):
    rows = [r for r in res["rows"] if r.get("set")]
    sets = [s for s in ("dev", "validation") if any(r["set"] == s for r in rows)]
    if not sets:
        out("summary: no levels rows in these results (run with --levels)")
        return
    for s in sets:
        rs = [r for r in rows if r["set"] == s]
        ok = [r for r in rs if not r["unresolved"] and r["ratio"] == r["ratio"] and r["ratio"] != float("inf")]
        ratios = [r["ratio"] for r in ok]
        levels = sorted(set(r["level"] for r in rs))
        scenes = [sc for sc in res["scenes"] if (sc.get("tags") or {}).get("set") == s]
        out("")
        out("== summary, %s set: %d levels (%d scenes: %s), %d objects, %d resolved (%d n/r: the reference's "
            "noise exceeds the difference)" % (s.upper(), len(levels), len(scenes), ", ".join(
                sorted(set(sc["tags"]["layout"] for sc in scenes))), len(rs), len(ok), len(rs) - len(ok)))
        if ratios:
            out("  [%s] lbk/Cycles at equal CPU time over objects: median %.2f, 90th percentile %.2f, max %.2f; "
                "goal <= 0.5 met on %d of %d, lbk worse than Cycles (> 1) on %d" % (
                    s, quantile(ratios, 0.5), quantile(ratios, 0.9), max(ratios), sum(x <= 0.5 for x in ratios),
                    len(ratios), sum(x > 1 for x in ratios)))
            out("  [%s] worst five lbk/Cycles:" % s)
            for r in sorted(ok, key=lambda r: -r["ratio"])[:5]:
                out("    %5.2f  %-26s %-16s lbk %5.1f %% (bias %+5.1f %%) Cycles %5.1f %%  %s" % (
                    r["ratio"], r["scene"], r["object"][:16], 100 * r["lbk_err"], 100 * r["lbk_bias"],
                    100 * r["cycles_err"], likely_cause(r)))
        est = [(_est_ratio(r), r) for r in ok]
        est = [(x, r) for x, r in est if x == x]
        if est:
            xs = [x for x, _ in est]
            out("  [%s] lbk estimate / measured error (RMSE/RMS) over objects: median %.2f, 10th percentile %.2f, "
                "90th percentile %.2f; within 2x on %d of %d, under half (claims too little) on %d" % (
                    s, quantile(xs, 0.5), quantile(xs, 0.1), quantile(xs, 0.9),
                    sum(0.5 <= x <= 2 for x in xs), len(xs), sum(x < 0.5 for x in xs)))
            out("  [%s] five furthest from 1:" % s)
            for x, r in sorted(est, key=lambda e: -abs(math.log(e[0])) if e[0] > 0 else -1e9)[:5]:
                out("    %5.2f  %-26s %-16s estimate %5.1f %%, measured %5.1f %%  %s" % (
                    x, r["scene"], r["object"][:16], 100 * r["lbk_est"], 100 * r["lbk_err_rms"], likely_cause(r)))
        sx = [sc["lbk_est"] / sc["all_texels"]["lbk_err_rms"] for sc in scenes
              if sc["all_texels"]["lbk_err_rms"] > 0]
        if sx:
            out("  [%s] per bake (all texels): estimate / measured median %.2f, min %.2f, max %.2f over %d scenes" % (
                s, quantile(sx, 0.5), min(sx), max(sx), len(sx)))


def main():
    ap = argparse.ArgumentParser(description="summary of a levels run")
    ap.add_argument("results")
    ap.add_argument("--out", default="")
    opt = ap.parse_args()
    lines = []

    def out(s):
        print(s, flush=True)
        lines.append(s)
    summarise(json.load(open(opt.results)), out)
    if opt.out:
        with open(opt.out, "w") as f:
            f.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
