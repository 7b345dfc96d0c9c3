#!/usr/bin/python3
"""The satellite over 1000 s (issue 61's table): for each method, the CPU time of the run, the largest
|E(t) - E(0)| / |E(0)| and the largest |L(t) - L(0)| / |L(0)| (angular momentum about the inertial
origin, the vector's change over its norm), each run by `soadyn run` (build/soadyn) and read back
from its file; then the CPU per step of variational against rk4 on the satellite and on the
50-DOF humanoid (tools/humanoid_urdf.py, free root, a seeded random q̇, gravity, 0.5 s at 1 ms).
Writes tools/results/long_horizon.md (Markdown tables) and prints it.  With --chart, also
tools/results/long_horizon.png: the energy error and the conserved momentum's error against time on
log axes, 10⁶ steps of every fixed-step method that takes the scene (and CVODE Adams at rtol 1e-10),
on the satellite (|ΔL|/|L|, 1000 s at 1 ms), the heavy top (|ΔL_z|/|L_z| about the vertical through
the pivot, 100 s at 0.1 ms) and the double pendulum (energy only, 1000 s at 1 ms); its data in
long_horizon.csv.  Several minutes of CPU.

    tools/long_horizon.py [--t-end 1000] [--scene satellite_two_arrays] [--out tools/results/long_horizon.md] [--chart]
"""
import argparse
import os
import re
import subprocess
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))

# (label, method, its options)
RUNS = [
    ("cvode-adams, rtol 1e-10", "cvode-adams", ["--rtol", "1e-10", "--atol", "1e-12"]),
    ("rk4, dt 0.1", "rk4", ["--dt", "0.1"]),
    ("implicit-midpoint, dt 0.1", "implicit-midpoint", ["--dt", "0.1"]),
    ("semi-implicit-euler, dt 0.01", "semi-implicit-euler", ["--dt", "0.01"]),
    ("variational, dt 0.1", "variational", ["--dt", "0.1"]),
    ("variational, dt 0.01", "variational", ["--dt", "0.01"]),
    # the bus's own linear velocity zeroed: the satellite stays within ~10 m of the origin, where the
    # algorithms' quantities about the origin carry less rounding
    ("variational, dt 0.1, bus not translating", "variational",
     ["--dt", "0.1", "--qd", "0.01,0.02,0.05,0,0,0,0.1,-0.05"]),
]


def soadyn_run(model, out, method, t_end, output_dt, options):
    """`soadyn run`: (CPU s, steps, Newton iterations, status) or (None, …, its last error line)"""
    cmd = [SOADYN, "run", model, "-o", out, "--method", method, "--t-end", str(t_end), "--output-dt", str(output_dt),
           "--log", "energy,momentum"] + options
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, None, None, (p.stderr or p.stdout).strip().splitlines()[-1]
    number = lambda name: float(re.search(name + r"\s+([0-9.eE+-]+)", p.stdout).group(1))
    return (number("CPU time"), number("steps"), number("nonlinear iterations"),
            re.search(r"status\s+(.*)", p.stdout).group(1))


def run(scene, method, options, t_end, output_dt=1.0):
    """(CPU s, max |ΔE|/|E0|, max |ΔL|/|L0| (nan where L0 = 0), the run's status line)"""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run.h5")
        cpu, _, _, status = soadyn_run(os.path.join(ROOT, "scenarios", scene + ".yaml"), out, method, t_end, output_dt,
                                       options)
        if cpu is None:
            return None, None, None, status
        with h5py.File(out, "r") as f:
            E = np.asarray(f["/energy/total"][...]).ravel()
            L = np.asarray(f["/momentum/angular"][...]).reshape(-1, 3)
    if not (np.all(np.isfinite(E)) and np.all(np.isfinite(L))):
        return None, None, None, "not finite"
    dE = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    L0 = np.linalg.norm(L[0])  # zero where the scene starts at rest (the double pendulum)
    dL = float(np.max(np.linalg.norm(L - L[0], axis=1)) / L0) if L0 > 0 else float("nan")
    return cpu, dE, dL, status


def step_costs():
    """CPU per step, variational against rk4, on the satellite and the humanoid (one run each)"""
    lines = ["", "CPU per step (one run each; Newton iterations per step for variational)", "",
             "| model | nv | rk4 | variational | ratio | iterations |", "|---|---|---|---|---|---|"]
    rng = np.random.default_rng(61)
    with tempfile.TemporaryDirectory() as tmp:
        urdf = os.path.join(tmp, "humanoid.urdf")
        subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "tools", "humanoid_urdf.py"), "-o", urdf], check=True,
                       capture_output=True)
        qd = ",".join(f"{x:.3f}" for x in rng.uniform(-0.5, 0.5, 56))
        cases = [("satellite_two_arrays (dt 0.1, 1000 s)", os.path.join(ROOT, "scenarios", "satellite_two_arrays.yaml"), 8,
                  ["--dt", "0.1"], 1000.0),
                 ("humanoid, free root (dt 1 ms, 0.5 s)", urdf, 56, ["--dt", "1e-3", "--free-root", "--qd", qd], 0.5)]
        for label, model, nv, options, t_end in cases:
            out = os.path.join(tmp, "run.h5")
            cpu_rk, steps_rk, _, status_rk = soadyn_run(model, out, "rk4", t_end, t_end, options)
            cpu_v, steps_v, it_v, status_v = soadyn_run(model, out, "variational", t_end, t_end, options)
            if cpu_rk is None or cpu_v is None:
                lines.append(f"| {label} | {nv} | {status_rk} | {status_v} | | |")
            else:
                a, b = cpu_rk / steps_rk * 1e6, cpu_v / steps_v * 1e6
                lines.append(f"| {label} | {nv} | {a:.3g} µs | {b:.3g} µs | {b / a:.2g} | {it_v / steps_v:.2f} |")
            print(lines[-1], flush=True)
    return lines


# the chart's scenes: (scene, dt, t_end, the momentum drawn: "L" the angular vector, "Lz" its z, None)
CHART = [("satellite_two_arrays", 1e-3, 1000.0, "L"), ("heavy_top", 1e-4, 100.0, "Lz"),
         ("double_pendulum", 1e-3, 1000.0, None)]
CHART_METHODS = ["cvode-adams", "semi-implicit-euler", "symplectic-euler", "rk4", "implicit-midpoint", "variational"]


def chart_runs(tmp):
    """per scene and method: (t, |ΔE|/|E0|, momentum error or None, CPU s); a refused method is left out"""
    data = {}
    for scene, dt, t_end, which in CHART:
        for method in CHART_METHODS:
            out = os.path.join(tmp, f"{scene}-{method}.h5")
            options = ["--rtol", "1e-10", "--atol", "1e-12"] if method.startswith("cvode") else ["--dt", repr(dt)]
            cpu, _, _, status = soadyn_run(os.path.join(ROOT, "scenarios", scene + ".yaml"), out, method, t_end,
                                           t_end / 1000, options)
            if cpu is None:
                print(f"{scene} {method}: {status}", flush=True)
                continue
            with h5py.File(out, "r") as f:
                t = np.asarray(f["/time"][...]).ravel()
                E = np.asarray(f["/energy/total"][...]).ravel()
                L = np.asarray(f["/momentum/angular"][...]).reshape(-1, 3)
            dE = np.abs(E - E[0]) / abs(E[0])
            dL = None
            if which == "L":
                dL = np.linalg.norm(L - L[0], axis=1) / np.linalg.norm(L[0])
            elif which == "Lz":
                dL = np.abs(L[:, 2] - L[0, 2]) / abs(L[0, 2])
            data[(scene, method)] = (t, dE, dL, cpu)
            print(f"{scene} {method}: CPU {cpu:.3g} s, max |ΔE|/E {dE.max():.2g}"
                  + ("" if dL is None else f", max momentum error {dL.max():.2g}"), flush=True)
    return data


def chart(png, csv_path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with tempfile.TemporaryDirectory() as tmp:
        data = chart_runs(tmp)
    fig, axes = plt.subplots(2, len(CHART), figsize=(5 * len(CHART), 7.5), squeeze=False)
    rows = ["scene,method,t,energy_error,momentum_error"]
    for c, (scene, dt, t_end, which) in enumerate(CHART):
        for method in CHART_METHODS:
            if (scene, method) not in data:
                continue
            t, dE, dL, cpu = data[(scene, method)]
            label = f"{method} ({'rtol 1e-10' if method.startswith('cvode') else f'dt {dt:g}'}, {cpu:.2g} s)"
            keep = t > 0
            color = f"C{CHART_METHODS.index(method)}"  # one colour per method on every panel
            axes[0][c].loglog(t[keep], np.maximum(dE[keep], 1e-17), label=label, lw=1, color=color)
            if dL is not None:
                axes[1][c].loglog(t[keep], np.maximum(dL[keep], 1e-17), label=label, lw=1, color=color)
            # the CSV: about 150 samples per curve, spaced evenly on the log axis
            for k in np.unique(np.round(np.logspace(0, np.log10(len(t) - 1), 150)).astype(int)):
                rows.append(f"{scene},{method},{t[k]:.9g},{dE[k]:.6g},{'' if dL is None else f'{dL[k]:.6g}'}")
        axes[0][c].set_title(f"{scene}: 10⁶ steps")
        axes[0][c].set_ylabel("|E(t) − E(0)| / |E(0)|")
        axes[1][c].set_ylabel({"L": "|L(t) − L(0)| / |L(0)|", "Lz": "|L_z(t) − L_z(0)| / |L_z(0)|"}.get(which, ""))
        if which is None:
            axes[1][c].text(0.5, 0.5, "no momentum conserved (the pivot and gravity)", ha="center",
                            transform=axes[1][c].transAxes)
        for r in (0, 1):
            axes[r][c].set_xlabel("t (s)")
            axes[r][c].grid(True, which="major", alpha=0.3)
        axes[0][c].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    with open(csv_path, "w") as f:
        f.write("\n".join(rows) + "\n")
    print(f"wrote {png} and {csv_path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=1000.0)
    ap.add_argument("--scene", default="satellite_two_arrays")
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "results", "long_horizon.md"))
    ap.add_argument("--chart", action="store_true", help="also the 10⁶-step chart beside --out (.png, .csv)")
    a = ap.parse_args()
    lines = [f"`{a.scene}` over {a.t_end:g} s (`tools/long_horizon.py`; CPU of one run on a shared 2-core machine)",
             "", "| method | CPU | max abs ΔE / E | max abs ΔL / L |", "|---|---|---|---|"]
    for label, method, options in RUNS:
        cpu, dE, dL, status = run(a.scene, method, options, a.t_end)
        if cpu is None:
            lines.append(f"| {label} | — | {status} | |")
        else:
            lines.append(f"| {label} | {cpu * 1e3:.3g} ms | {dE:.2g} | {dL:.2g} |")
        print(lines[-1], flush=True)
    lines += step_costs()
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    if a.chart:
        stem = os.path.splitext(a.out)[0]
        chart(stem + ".png", stem + ".csv")


if __name__ == "__main__":
    main()
