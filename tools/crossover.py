#!/usr/bin/python3
"""Where structure-preserving methods overtake the others, measured (issue 61).

1. Long-horizon work-precision: the double pendulum (chaotic, so the energy error, not the
   trajectory's, is what a long run can be judged by) over T = 10³ and 10⁴ periods of its lowest
   small-oscillation mode (2.344 s: 𝓜 and ∂²V at q = 0 of scenarios/double_pendulum.yaml), each
   method at several steps or tolerances: the largest |E(t) − E(0)| / |E(0)| over the run against
   its CPU.  Then, per horizon and error target, the cheapest run that holds it: the crossover read
   off the data.
2. The satellite (satellite_two_arrays) over 1000 s: the CPU each method needs to hold
   |ΔL| / |L| ≤ 1e-10 (the step halved from 0.2 s, or the tolerance divided by 10 from 1e-7, until
   it holds; fixed steps stop at 10⁶).

Each run is `soadyn run` (build/soadyn, or $SOADYN), read back from its file.  Writes
tools/results/crossover.{md,png,csv}.  About 10 minutes of one core.

    tools/crossover.py [--out tools/results/crossover.md] [--quick]
"""
import argparse
import os

import long_horizon
from long_horizon import ROOT

PERIOD = 2.344  # s: the double pendulum's lowest small-oscillation mode
HORIZONS = [1000, 10000]  # periods
# per method: the option it is varied by and its values (coarse to fine)
SETTINGS = {
    "cvode-adams": ("rtol", [1e-7, 1e-9, 1e-11, 1e-13]),
    "rk4": ("dt", [0.04, 0.02, 0.01, 0.005]),
    "implicit-midpoint": ("dt", [0.04, 0.02, 0.01, 0.005]),
    "symplectic-euler": ("dt", [0.01, 0.005, 0.0025]),
    "variational": ("dt", [0.04, 0.02, 0.01, 0.005]),
}
TARGETS = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]


def options(method, value):
    if method.startswith("cvode"):
        return ["--rtol", repr(value), "--atol", repr(value * 1e-2)]
    return ["--dt", repr(value)]


def run(scene, method, value, t_end):
    """(CPU s, max |ΔE|/|E0|, max |ΔL|/|L0|) or None, and the run's status line"""
    cpu, dE, dL, status = long_horizon.run(scene, method, options(method, value), t_end, output_dt=t_end / 2000)
    return (None if cpu is None else (cpu, dE, dL)), status


def label(method, value):
    return f"{method}, {'rtol' if method.startswith('cvode') else 'dt'} {value:g}"


def work_precision(quick):
    """{horizon: [(method, value, CPU, error)]} on the double pendulum"""
    data = {}
    for periods in HORIZONS[:1] if quick else HORIZONS:
        rows = []
        for method, (_, values) in SETTINGS.items():
            for value in (values[:2] if quick else values):
                r, status = run("double_pendulum", method, value, periods * PERIOD)
                if r is None:
                    print(f"{periods} periods, {label(method, value)}: {status}", flush=True)
                    continue
                rows.append((method, value, r[0], r[1]))
                print(f"{periods} periods, {label(method, value)}: CPU {r[0]:.3g} s, max |ΔE|/E {r[1]:.2g}", flush=True)
        data[periods] = rows
    return data


def momentum_budget(quick):
    """per method: (the setting that first holds |ΔL|/L ≤ 1e-10 over 1000 s, CPU, ΔL) or the finest tried"""
    searches = {"cvode-adams": [1e-7 / 10**k for k in range(7)], "cvode-bdf": [1e-7 / 10**k for k in range(7)]}
    for method in ("rk4", "variational", "implicit-midpoint", "semi-implicit-euler"):
        searches[method] = [0.2 / 2**k for k in range(8)]  # to 1.6e-3 s: 6.4·10⁵ steps
    out = []
    for method, values in searches.items():
        best = None
        for value in (values[:3] if quick else values):
            r, status = run("satellite_two_arrays", method, value, 1000.0)
            if r is None:
                print(f"satellite {label(method, value)}: {status}", flush=True)
                continue
            print(f"satellite {label(method, value)}: CPU {r[0]:.3g} s, |ΔL|/L {r[2]:.2g}", flush=True)
            best = (method, value, r[0], r[2], r[2] <= 1e-10)
            if best[4]:
                break
        if best:
            out.append(best)
    return out


def write(data, budget, md, png, csv):
    lines = ["Long horizons: the double pendulum's largest relative energy error over T against CPU "
             f"(`tools/crossover.py`; a period is {PERIOD} s; CPU of one run on a shared 2-core machine)", ""]
    csv_rows = ["periods,method,setting,cpu_s,max_energy_error"]
    for periods, rows in data.items():
        lines += [f"T = {periods} periods ({periods * PERIOD:.0f} s)", "", "| run | CPU | max abs ΔE / E |", "|---|---|---|"]
        for method, value, cpu, err in rows:
            lines.append(f"| {label(method, value)} | {cpu:.3g} s | {err:.2g} |")
            csv_rows.append(f"{periods},{method},{value!r},{cpu:.6g},{err:.6g}")
        lines += ["", "The cheapest run that holds each energy error:", "", "| max abs ΔE / E ≤ | cheapest run | CPU |",
                  "|---|---|---|"]
        for target in TARGETS:
            held = [r for r in rows if r[3] <= target]
            if held:
                m, v, c, _ = min(held, key=lambda r: r[2])
                lines.append(f"| {target:g} | {label(m, v)} | {c:.3g} s |")
            else:
                lines.append(f"| {target:g} | none of the runs | |")
        lines.append("")
    lines += ["The satellite over 1000 s: the CPU each method needs to hold |ΔL| / |L| ≤ 1e-10 (the first "
              "setting, coarse to fine, that holds it)", "", "| method | setting | CPU | max abs ΔL / L |", "|---|---|---|---|"]
    for method, value, cpu, dL, held in budget:
        setting = f"{'rtol' if method.startswith('cvode') else 'dt'} {value:g}"
        lines.append(f"| {method} | {setting if held else 'not held; finest tried ' + setting} | {cpu:.3g} s | {dL:.2g} |")
    with open(md, "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(csv, "w") as f:
        f.write("\n".join(csv_rows) + "\n")
    print("\n".join(lines))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(data), figsize=(6 * len(data), 4.8), squeeze=False)
    for ax, (periods, rows) in zip(axes[0], data.items()):
        for k, method in enumerate(SETTINGS):
            pts = [(c, e, v) for m, v, c, e in rows if m == method]
            if not pts:
                continue
            ax.loglog([p[0] for p in pts], [max(p[1], 1e-17) for p in pts], "o-", color=f"C{k}", label=method, lw=1)
            for c, e, v in pts:
                ax.annotate(f"{v:g}", (c, max(e, 1e-17)), fontsize=6, xytext=(3, 3), textcoords="offset points")
        ax.set_title(f"double pendulum, T = {periods} periods ({periods * PERIOD:.0f} s)")
        ax.set_xlabel("CPU (s)")
        ax.set_ylabel("max |E(t) − E(0)| / |E(0)|")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"wrote {md}, {png} and {csv}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "results", "crossover.md"))
    ap.add_argument("--quick", action="store_true", help="two settings per method, 10³ periods, three budget steps (a check)")
    a = ap.parse_args()
    data = work_precision(a.quick)
    budget = momentum_budget(a.quick)
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    stem = os.path.splitext(a.out)[0]
    write(data, budget, a.out, stem + ".png", stem + ".csv")


if __name__ == "__main__":
    main()
