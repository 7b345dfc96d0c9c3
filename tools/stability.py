#!/usr/bin/python3
"""Stability study: where each method fails.

For each fixed-step method (the implicit midpoint rule with full and with simplified Newton) and
scenario (the note's examples, the tumbling T-handle in place of the satellite, the stiff arm and
the flexible satellite), bisect (in log dt) the largest step that keeps the energy balance bounded
over a long run -- completed, and E(t) - E(0) - W(t) within ±5 % of max(|E0|, peak T) (W: the work
of torques and dampers) -- then classify what happens at
twice that step: blow-up (non-finite state), Newton fails (an implicit step does not converge),
energy growth, numerical damping.
For CVODE, the energy-balance error and work as rtol loosens.  Writes tools/results/stability.{md,csv,png}.

    tools/stability.py [--t-end T] [--out tools/results]
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import runs  # noqa: E402

SCENES = ["pendulum_on_cart", "double_pendulum", "tumbling_t_handle", "three_link_arm", "stiff_arm",
          "flexible_satellite"]
T_END_CAP = {"flexible_satellite": 5.0}  # 17 bodies: its runs stop at 5 s (the fast modes show within it)
BOUND = 0.05
DT_LO, DT_HI = 1e-6, 1.0


def bounded(r, scene):
    if not r["ok"]:
        return False
    e = r["E_rel"]
    # the energy-balance error: a damped scene's energy may fall, but only by the dampers' work
    return e.max() <= BOUND and e.min() >= -BOUND


def mode(r, scene):
    if not r["ok"]:  # an implicit method's Newton iteration may fail before anything blows up
        return "Newton fails" if "did not converge" in r["status"] else "blow-up"
    e = r["E_rel"]
    if e.max() > BOUND:
        return f"energy growth ({e.max():+.0%})"
    if e.min() < -BOUND:
        return f"numerical damping ({e.min():+.0%})"
    return "bounded"


def largest_stable(scene, method, t_end):
    lo, hi = DT_LO, DT_HI
    t_end = min(t_end, T_END_CAP.get(scene, t_end))
    r_hi = runs.run(scene, method, t_end=t_end, dt=hi, output_dt=hi)
    if bounded(r_hi, scene):
        return hi, "stable up to the search bound"
    for _ in range(9):
        mid = math.sqrt(lo * hi)
        if bounded(runs.run(scene, method, t_end=t_end, dt=mid, output_dt=max(mid, 0.01)), scene):
            lo = mid
        else:
            hi = mid
    beyond = runs.run(scene, method, t_end=t_end, dt=2 * lo, output_dt=max(2 * lo, 0.01))
    return lo, mode(beyond, scene)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--t-end", type=float, default=20.0, help="length of each run, s (default 20)")
    ap.add_argument("--out", default=os.path.join(runs.ROOT, "tools", "results"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    from concurrent.futures import ThreadPoolExecutor
    cells = [(s, m) for s in SCENES for m in runs.FIXED if not runs.refuses(s, m)]  # symplectic-euler: no quaternions
    with ThreadPoolExecutor(2) as ex:
        found = list(ex.map(lambda c: largest_stable(c[0], c[1], args.t_end), cells))
    table = dict(zip(cells, found))

    cvode = runs.run_many([dict(scenario=s, method=m, t_end=min(args.t_end, T_END_CAP.get(s, args.t_end)), rtol=rt)
                           for s in SCENES for m in runs.CVODE for rt in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)])

    capped = ", ".join(f"{k} {min(v, args.t_end):g} s" for k, v in T_END_CAP.items())
    lines = [f"# Stability study (runs of {args.t_end:g} s, {capped}; bounded: |E(t) - E(0) - W(t)| <= {BOUND:.0%} of max(|E0|, peak T), W the work of dampers)", "",
             "Largest step that keeps the energy bounded, and what happens at twice that step:", "",
             "| scenario | " + " | ".join(runs.label(m) for m in runs.FIXED) + " |", "|---" * (len(runs.FIXED) + 1) + "|"]
    for s in SCENES:
        lines.append(f"| {s} | " + " | ".join(f"{table[(s, m)][0]:.3g} s: {table[(s, m)][1]}" if (s, m) in table
                                              else "refused (free or ball joint)" for m in runs.FIXED) + " |")
    lines += ["", "CVODE as rtol loosens: max relative energy-balance error |E(t) - E(0) - W(t)| / max(|E0|, peak T)",
              "(W the work of torques and dampers) / RHS evaluations:", "",
              "| scenario | method | " + " | ".join(f"rtol {rt:g}" for rt in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)) + " |",
              "|---" * 7 + "|"]
    for s in SCENES:
        for m in runs.CVODE:
            rs = [r for r in cvode if r["scenario"] == s and r["method"] == m]
            lines.append(f"| {s} | {runs.label(m)} | " + " | ".join(
                (f"{r['balance_error']:.1e} / {r['rhs']}" if r["ok"] else f"failed: {r['status'][:60]}") for r in rs) + " |")
    md = "\n".join(lines) + "\n"
    with open(os.path.join(args.out, "stability.md"), "w") as f:
        f.write(md)
    with open(os.path.join(args.out, "stability.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scenario", "method", "max_stable_dt", "beyond"])
        for (s, m), (dt, why) in table.items():
            w.writerow([s, m, f"{dt:.4g}", why])
    print(md)

    fig, ax = plt.subplots(figsize=(10, 4.2))
    width = 0.8 / len(runs.FIXED)
    x = np.arange(len(SCENES))
    for k, m in enumerate(runs.FIXED):
        vals = [table[(s, m)][0] if (s, m) in table else float("nan") for s in SCENES]
        ax.bar(x + (k - (len(runs.FIXED) - 1) / 2) * width, vals, width, label=runs.label(m), color=f"C{k + 2}")
    ax.set_yscale("log")
    ax.set_xticks(x, SCENES, fontsize=8)
    ax.set_ylabel("largest step with bounded energy [s]")
    ax.axhline(DT_HI, color="gray", lw=0.5)
    ax.set_title(f"Where fixed-step methods fail ({args.t_end:g} s runs, {capped}; bars at {DT_HI:g} s: stable at every step tried)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y", which="both")
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "stability.png"), dpi=80)


if __name__ == "__main__":
    main()
