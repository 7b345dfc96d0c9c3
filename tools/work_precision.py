#!/usr/bin/python3
"""Work-precision charts: for each of the note's four scenarios, every method over a sweep
(CVODE Adams and BDF over rtol 1e-3 ... 1e-12; fixed-step methods over step sizes from well
inside to two decades past their stability limit), error at t_end against a reference run
(CVODE Adams, rtol 1e-13) and energy-balance error, against CPU time.  One PNG per scenario in
tools/results/, the data as CSV beside it.

    tools/work_precision.py [--t-end T] [--out tools/results] [--scenes NAME ...]
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

import json  # noqa: E402
import subprocess  # noqa: E402

import runs  # noqa: E402

MUJOCO_RK4 = os.path.join(runs.ROOT, "build", "soadyn_mujoco_rk4")  # built when MuJoCo is installed
FIXED_BASE = {"pendulum_on_cart", "double_pendulum", "three_link_arm"}


def mujoco_rk4(scene, dt, t_end):
    """MuJoCo's RK4 on the same scene (same 𝓜 checked by the tool), or None"""
    p = subprocess.run([MUJOCO_RK4, os.path.join(runs.SCENARIOS, scene + ".yaml"), repr(dt), repr(t_end)],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        return None
    r = json.loads(p.stdout)
    r["q"], r["qd"], r["dt"] = np.array(r["q"]), np.array(r["qd"]), dt
    r["ok"] = bool(np.abs(np.concatenate([r["q"], r["qd"]])).max() < 1e300)
    return r

SCENES = ["pendulum_on_cart", "double_pendulum", "satellite_two_arrays", "three_link_arm", "tumbling_t_handle",
          "flexible_satellite"]
RTOLS = [10.0 ** -k for k in range(3, 13)]
DTS = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 1e-1, 3e-1]


def state_error(r, ref):
    if not r["ok"]:
        return float("nan")
    e = np.concatenate([r["q"] - ref["q"], r["qd"] - ref["qd"]])
    return float(np.abs(e).max())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--t-end", type=float, default=5.0, help="horizon of every run, s (default 5)")
    ap.add_argument("--out", default=os.path.join(runs.ROOT, "tools", "results"))
    ap.add_argument("--scenes", nargs="+", choices=SCENES, default=SCENES, help="redo only these scenes' charts")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for scene in args.scenes:
        ref = runs.run(scene, "cvode-adams", t_end=args.t_end, rtol=1e-13, output_dt=args.t_end)
        jobs = [dict(scenario=scene, method=m, t_end=args.t_end, rtol=rt, output_dt=args.t_end)
                for m in runs.CVODE for rt in RTOLS]
        jobs += [dict(scenario=scene, method=m, t_end=args.t_end, dt=dt, output_dt=args.t_end)
                 for m in runs.FIXED for dt in DTS if not (runs.split(m)[0] == "implicit-midpoint" and dt < 1e-3)
                 and not runs.refuses(scene, m)]  # symplectic-euler refuses free and ball joints
        results = runs.run_many(jobs)
        with open(os.path.join(args.out, f"wp_{scene}.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["method", "rtol", "dt", "cpu_seconds", "rhs_evals", "state_error", "balance_error", "status"])
            for r in results:
                w.writerow([r["method"], r["rtol"] or "", r["dt"] or "", f"{r['cpu']:.6g}", r.get("rhs", ""),
                            f"{state_error(r, ref):.3e}", f"{r.get('balance_error', float('nan')):.3e}", r["status"]])
        fig, ax = plt.subplots(1, 2, figsize=(12, 4.6))
        for k, m in enumerate(runs.CVODE + runs.FIXED):
            rs = [r for r in results if r["method"] == m and r["ok"]]
            if not rs:
                continue
            cpu = [max(r["cpu"], 1e-5) for r in rs]
            style = "o--" if "/" in m else "o-"  # the variants (DQ Jacobian, simplified Newton) dashed
            ax[0].loglog(cpu, [max(state_error(r, ref), 1e-16) for r in rs], style, color=f"C{k}", ms=3, label=runs.label(m))
            ax[1].loglog(cpu, [max(r["balance_error"], 1e-16) for r in rs], style, color=f"C{k}", ms=3, label=runs.label(m))
            failed = [r for r in results if r["method"] == m and not r["ok"]]
            if failed:
                ax[0].plot([], [], " ", label=f"  {m}: {len(failed)} runs blew up (dt >= {min(r['dt'] or 0 for r in failed):g})")
        if os.path.exists(MUJOCO_RK4) and scene in FIXED_BASE:
            peer = [r for r in (mujoco_rk4(scene, dt, args.t_end) for dt in DTS) if r and r["ok"]]
            with open(os.path.join(args.out, f"wp_{scene}.csv"), "a", newline="") as f:
                for r in peer:
                    f.write(f"mujoco-rk4,,{r['dt']},{r['cpu']:.6g},,{state_error(r, ref):.3e},,completed\n")
            if peer:
                ax[0].loglog([max(r["cpu"], 1e-5) for r in peer], [max(state_error(r, ref), 1e-16) for r in peer],
                             "x--", color="k", ms=5, label="MuJoCo 2.2 rk4 (peer)")
        ax[0].set_title(f"{scene}: state error at t = {args.t_end:g} s vs CVODE rtol 1e-13")
        ax[1].set_title("max |E(t) - E(0) - W(t)| / max(|E0|, peak T)")
        for a in ax:
            a.set_xlabel("CPU time [s]")
            a.grid(alpha=0.3, which="both")
        ax[0].set_ylabel("max |y - y_ref|")
        ax[0].legend(fontsize=7)
        fig.tight_layout()
        png = os.path.join(args.out, f"wp_{scene}.png")
        fig.savefig(png, dpi=80)
        plt.close(fig)
        print(f"wrote {png}")


if __name__ == "__main__":
    main()
