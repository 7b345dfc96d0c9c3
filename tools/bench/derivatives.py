#!/usr/bin/python3
"""Derivative benchmark report: tools/results/derivatives.md.

1. Runs build/soadyn_bench_derivatives (configure with -DSOADYN_BUILD_BENCH=ON) and reports each
   derivative set's CPU time per call against N, chains, binary trees and legged free-floating
   robots, as a multiple of one O(N) forward dynamics at the same N, with exponents fitted over
   N = 16..256; and the forward derivatives and 𝓜⁻¹ alone on chains in ns, with their fitted
   exponents.
2. Runs CVODE BDF at rtol 1e-8 with the analytic Jacobian and with difference quotients on the
   stiff scenes (scenarios/stiff_arm.yaml and scenarios/flexible_satellite.yaml): steps, RHS and
   Jacobian evaluations, CPU time, each the best of --repeat runs, analytic and DQ interleaved
   (the machines are shared), once logging every output_dt as the scene asks and once with a
   single output row (the integration alone: the same steps).

--bdf-only keeps the derivative tables of the existing derivatives.md and redoes part 2.
"""
import argparse
import json
import os
import re
import subprocess
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SETS = [("id_deriv", "∂τ/∂q, ∂τ/∂v (inverse dynamics)"),
        ("fd_deriv", "∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = 𝓜⁻¹ (forward dynamics)"),
        ("minverse", "𝓜⁻¹ alone (minverse)"),
        ("minverse_ltdl", "𝓜⁻¹ by 𝓜's LᵀDL against the identity"),
        ("jac_analytic", "∂f/∂y of ẏ = f(y), analytic (BDF, midpoint)"),
        ("jac_dq", "∂f/∂y by nq + nv difference quotients of f")]


def bench(binary, min_time, out_json):
    subprocess.run([binary, f"--benchmark_min_time={min_time}", "--benchmark_out_format=json",
                    f"--benchmark_out={out_json}"], check=True, stdout=subprocess.DEVNULL)
    with open(out_json) as f:
        data = json.load(f)
    series = {}
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    for b in data["benchmarks"]:
        name, n = b["name"].rsplit("/", 1)
        series.setdefault(name, {})[int(n)] = b["cpu_time"] * scale[b.get("time_unit", "ns")]
    return series, data.get("context", {})


def exponent(points, lo=15, hi=256):
    ns = sorted(n for n in points if lo <= n <= hi)
    return float(np.polyfit(np.log(ns), np.log([points[n] for n in ns]), 1)[0])


def run_bdf(soadyn, scenario, jacobian, rtol, out, extra=()):
    p = subprocess.run([soadyn, "run", scenario, "--method", "cvode-bdf", "--rtol", str(rtol), "--atol", str(rtol * 1e-2),
                        "--jacobian", jacobian, "-o", out, *extra], check=True, capture_output=True, text=True).stdout
    get = lambda key: float(re.search(key + r"\s+([0-9.e+-]+)", p).group(1))  # noqa: E731
    return {"steps": get("steps"), "rhs": get("RHS evaluations"), "jac": get("Jacobian evaluations"),
            "etf": get("error-test failures"), "nni": get("nonlinear iterations"), "cpu": get("CPU time")}


def bdf_section(soadyn, scenes, rtol, repeat, h5):
    """CVODE BDF, analytic Jacobian against difference quotients: best CPU of `repeat` interleaved runs."""
    from datetime import datetime, timezone
    lines = [f"## CVODE BDF at rtol {rtol:g} (atol {rtol * 1e-2:g}): analytic Jacobian vs difference quotients", "",
             f"{datetime.now(timezone.utc).isoformat(timespec='seconds')}, {os.cpu_count()} CPUs. Best CPU time of {repeat} runs "
             "of `soadyn run`, analytic and DQ interleaved. Output \"logged\": a row every output_dt as the scene",
             "asks (HDF5 logging in the CPU time); \"t_end\": `--output-dt` = t_end, one row at the end, the integration",
             "alone (CVODE sizes its first step from the first output time, so the step counts differ a little).",
             "RHS evaluations include CVODE's difference-quotient ones. Analytic: System::jacobian and Newton's I − γJ",
             "solved through its nv×nv Schur complement (NewtonSolver); DQ: CVODE's difference quotients and its",
             "dense LU of the whole state y = [q; v; W, D].", "",
             "| scene | size of y | output | Jacobian | steps | error-test failures | Newton iterations | RHS evals "
             "| Jacobian evals | CPU [s] | DQ / analytic CPU |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for scene in scenes:
        info = subprocess.run([soadyn, "inspect", scene, "--json"], check=True, capture_output=True, text=True).stdout
        nq, nv = (int(re.search(rf'"{k}": (\d+)', info).group(1)) for k in ("nq", "nv"))
        t_end = re.search(r"t_end:\s*([0-9.e+-]+)", open(scene).read()).group(1)
        modes = (("logged", ()), ("t_end", ("--output-dt", t_end)))
        best = {}
        for _ in range(repeat):
            for mode, extra in modes:
                for j in ("analytic", "dq"):
                    r = run_bdf(soadyn, scene, j, rtol, h5, extra)
                    key = (mode, j)
                    assert key not in best or best[key]["steps"] == r["steps"], "the steps changed between repeats"
                    if key not in best or r["cpu"] < best[key]["cpu"]:
                        best[key] = r
        for mode, _ in modes:
            for j in ("analytic", "dq"):
                r = best[(mode, j)]
                ratio = f"{r['cpu'] / best[(mode, 'analytic')]['cpu']:.2f}" if j == "dq" else ""
                lines.append(f"| {os.path.basename(scene)} | {nq + nv + 2} | {mode} | {j} | {r['steps']:.0f} | {r['etf']:.0f} | "
                             f"{r['nni']:.0f} | {r['rhs']:.0f} | {r['jac']:.0f} | {r['cpu']:.4f} | {ratio} |")
    lines.append("")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "results"))
    ap.add_argument("--min-time", default="0.1")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--bdf-only", action="store_true", help="keep the derivative tables, redo the BDF comparison")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    md = os.path.join(args.out, "derivatives.md")
    if args.bdf_only:
        with open(md) as f:
            lines = f.read().split("## CVODE BDF")[0].rstrip("\n").split("\n") + [""]
    else:
        lines = derivative_tables(args)

    soadyn = os.path.join(args.build, "soadyn")
    scenes = [os.path.join(ROOT, "scenarios", "flexible_satellite.yaml"), os.path.join(ROOT, "scenarios", "stiff_arm.yaml")]
    h5 = os.path.join(args.out, "derivatives_bdf.h5")
    lines += bdf_section(soadyn, scenes, args.rtol, args.repeat, h5)
    if os.path.exists(h5):
        os.remove(h5)
    with open(md, "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))
    return 0


def derivative_tables(args):
    series, ctx = bench(os.path.join(args.build, "soadyn_bench_derivatives"), args.min_time,
                        os.path.join(args.out, "derivatives.json"))
    lines = [f"# Derivatives of the dynamics ({ctx.get('date', '')}, {ctx.get('num_cpus', '?')} CPUs)", "",
             "CPU time per call as a multiple of one O(N) forward dynamics (kinematics, velocities, articulated-body",
             "q̈) at the same N; the last columns give that forward dynamics in ns and each set's growth exponent",
             "fitted over N = 16..256. tools/bench/derivatives.py wrote this file.", ""]
    for group in ("chain", "tree", "legged"):
        fd = series[f"{group}/fd"]
        ns = sorted(fd)
        legged = group == "legged"  # its argument is the legs' length: 6 + 4n DOFs, no exponent
        head = [f"nv={6 + 4 * n}" if legged else f"N={n}" for n in ns]
        fit = (lambda _: "") if legged else (lambda pts: f"{exponent(pts):.2f}")
        lines.append(f"| {'legged, free trunk and 4 legs' if legged else group}: set | " + " | ".join(head) + " | exponent |")
        lines.append("|---" * (len(ns) + 2) + "|")
        lines.append("| forward dynamics [ns] | " + " | ".join(f"{fd[n]:.0f}" for n in ns) + f" | {fit(fd)} |")
        for key, label in SETS:
            s = series[f"{group}/{key}"]
            lines.append(f"| {label} | " + " | ".join(f"{s[n] / fd[n]:.1f}×" for n in ns) + f" | {fit(s)} |")
        lines.append("")
    # the forward derivatives and 𝓜⁻¹ alone on chains in ns, with their exponents
    rows = [("fd_deriv", "∂q̈/∂q, ∂q̈/∂v, 𝓜⁻¹"), ("minverse", "𝓜⁻¹ alone (minverse)")]
    ns = [n for n in sorted(series["chain/fd_deriv"]) if 16 <= n <= 256]
    lines += ["The forward derivatives and 𝓜⁻¹ on chains, CPU ns per call (kinematics and velocities included), and the exponent",
              "fitted by least squares on log-log over N = 16..256 (issue 31: ≤ 2.1):", "",
              "| chain | " + " | ".join(f"N={n}" for n in ns) + " | exponent |", "|---" * (len(ns) + 2) + "|"]
    for key, label in rows:
        pts = series[f"chain/{key}"]
        lines.append(f"| {label} | " + " | ".join(f"{pts[n]:,.0f}" for n in ns) + f" | {exponent(pts):.2f} |")
    lines.append("")
    fd32, fdd32 = series["chain/fd"].get(32), series["chain/fd_deriv"].get(32)
    tree31 = series["tree/fd_deriv"][31] / series["tree/fd"][31]
    lines += [f"Forward-dynamics derivatives at N = 32 (chain): {fdd32 / fd32:.1f}× one forward dynamics "
              f"(target ≤ 10×); binary tree N = 31: {tree31:.1f}×.", ""]
    return lines


if __name__ == "__main__":
    sys.exit(main())
