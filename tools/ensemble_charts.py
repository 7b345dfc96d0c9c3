#!/usr/bin/python3
"""Charts from a sweep's results (soadyn sweep … -o DIR; DIR/results.h5).

- Work-precision with error bands: per method and step (simulation.dt) or tolerance
  (simulation.rtol), the median RHS evaluations against the median state error (vs the sweep's
  reference run), with the 10–90 % band over the ensemble's initial conditions.
- Stability map per method: step size × initial energy → fraction of runs that stay bounded
  (completed, and the relative energy-balance error never above --bound, 5 % as in tools/stability.py).

    tools/ensemble_charts.py DIR/results.h5 [-o OUTDIR] [--bound 0.05] [--energy-bins 10]

Writes OUTDIR/ensemble_wp.{png,csv} when the sweep has a reference and OUTDIR/ensemble_stability.{png,csv}
when it varies simulation.dt.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(path):
    import h5py
    with h5py.File(path, "r") as f:
        g = f["cases"]
        return {k: (g[k].asstr()[()] if h5py.check_string_dtype(g[k].dtype) else g[k][()]) for k in g}


def work_precision(t, out):
    knob = "simulation.dt" if "simulation.dt" in t else "simulation.rtol" if "simulation.rtol" in t else None
    if knob is None or not np.any(np.isfinite(t["state_error"])):
        print("work-precision: needs a reference and a varied simulation.dt or simulation.rtol", file=sys.stderr)
        return False
    methods = t["simulation.method"] if "simulation.method" in t else np.array(["(base)"] * len(t["case"]))
    rows = []
    fig, ax = plt.subplots(figsize=(7, 5))
    for m in dict.fromkeys(methods):
        pts = []
        for k in sorted(set(t[knob][methods == m])):
            sel = (methods == m) & (t[knob] == k) & t["completed"] & np.isfinite(t["state_error"])
            if sel.sum() == 0:
                continue
            err = np.maximum(t["state_error"][sel], 1e-17)
            p10, p50, p90 = np.percentile(err, [10, 50, 90])
            work = float(np.median(t["rhs_evals"][sel]))
            pts.append((work, p10, p50, p90))
            rows.append([m, knob, k, int(sel.sum()), work, p10, p50, p90])
        if not pts:
            continue
        w, lo, med, hi = map(np.array, zip(*sorted(pts)))
        line, = ax.loglog(w, med, "o-", label=f"{m} (median)")
        ax.fill_between(w, lo, hi, color=line.get_color(), alpha=0.2, lw=0)
    n_ic = len(t["case"]) // max(1, len(rows))
    ax.set_xlabel("RHS evaluations (median per point)")
    ax.set_ylabel("max state error vs reference")
    ax.set_title(f"median and 10–90 % band over ~{n_ic} runs per point", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "ensemble_wp.png"), dpi=120)
    plt.close(fig)
    with open(os.path.join(out, "ensemble_wp.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "knob", "value", "runs", "median_rhs_evals", "p10_error", "median_error", "p90_error"])
        w.writerows(rows)
    return True


def stability_map(t, out, bound, nbins):
    if "simulation.dt" not in t:
        print("stability map: needs a varied simulation.dt", file=sys.stderr)
        return False
    methods = t["simulation.method"] if "simulation.method" in t else np.array(["(base)"] * len(t["case"]))
    bounded = t["completed"] & (t["max_energy_balance_error"] <= bound)
    e0 = t["initial_energy"]
    edges = np.quantile(e0[np.isfinite(e0)], np.linspace(0, 1, nbins + 1))
    edges[-1] = np.nextafter(edges[-1], np.inf)
    dts = np.array(sorted(set(t["simulation.dt"])))
    ms = list(dict.fromkeys(methods))
    fig, axes = plt.subplots(1, len(ms), figsize=(3.6 * len(ms) + 1, 3.8), squeeze=False, sharey=True)
    rows = []
    for ax, m in zip(axes[0], ms):
        frac = np.full((nbins, len(dts)), np.nan)
        for j, dt in enumerate(dts):
            for i in range(nbins):
                sel = (methods == m) & (t["simulation.dt"] == dt) & (e0 >= edges[i]) & (e0 < edges[i + 1])
                if sel.any():
                    frac[i, j] = bounded[sel].mean()
                    rows.append([m, dt, edges[i], edges[i + 1], int(sel.sum()), frac[i, j]])
        ax.pcolormesh(np.arange(len(dts) + 1), edges, frac, vmin=0, vmax=1, cmap="RdYlGn", shading="flat")
        ax.set_xticks(np.arange(len(dts)) + 0.5)
        ax.set_xticklabels([f"{d:.0e}" for d in dts], rotation=60, fontsize=7)
        ax.set_title(m, fontsize=9)
        ax.set_xlabel("dt, s")
    axes[0][0].set_ylabel("initial energy E0, J")
    sm = plt.cm.ScalarMappable(cmap="RdYlGn", norm=plt.Normalize(0, 1))
    fig.colorbar(sm, ax=axes[0].tolist(), label=f"fraction bounded (|ΔE| ≤ {bound:g} of scale)")
    fig.suptitle(f"stability over the ensemble ({len(t['case'])} runs)", fontsize=10)
    fig.savefig(os.path.join(out, "ensemble_stability.png"), dpi=120, bbox_inches="tight")
    plt.close(fig)
    with open(os.path.join(out, "ensemble_stability.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "dt", "energy_lo", "energy_hi", "runs", "fraction_bounded"])
        w.writerows(rows)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", help="a sweep's results.h5")
    ap.add_argument("-o", "--out", default=".", help="directory for the charts (default .)")
    ap.add_argument("--bound", type=float, default=0.05, help="largest relative energy-balance error that counts as bounded")
    ap.add_argument("--energy-bins", type=int, default=10, help="initial-energy bins (quantiles) of the stability map")
    a = ap.parse_args()
    try:
        t = read(a.results)
    except (OSError, KeyError) as e:
        print(f"ensemble_charts: error: {a.results}: not a sweep's results.h5 ({e})", file=sys.stderr)
        return 2
    os.makedirs(a.out, exist_ok=True)
    made = [work_precision(t, a.out), stability_map(t, a.out, a.bound, a.energy_bins)]
    return 0 if any(made) else 1


if __name__ == "__main__":
    sys.exit(main())
