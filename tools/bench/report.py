#!/usr/bin/python3
"""Turn a Google Benchmark JSON of soadyn_bench into bench.csv, bench.md (exponents, ratios,
crossovers) and bench.png (log-log time against N)."""
import argparse
import collections
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        data = json.load(f)
    series = collections.defaultdict(dict)  # "chain/bias" -> {N: ns}
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        name, n = b["name"].rsplit("/", 1)
        series[name][int(n)] = b["real_time"] * scale[b.get("time_unit", "ns")]
    return series, data.get("context", {})


def exponent(points, lo=16, hi=256):
    ns = sorted(n for n in points if lo <= n <= hi)
    if len(ns) < 2:
        return float("nan")
    x, y = np.log([float(n) for n in ns]), np.log([points[n] for n in ns])
    return float(np.polyfit(x, y, 1)[0])


def crossover(fast, slow):
    """smallest N from which `fast` is faster than `slow` at every larger N measured"""
    ns = sorted(set(fast) & set(slow))
    for i, n in enumerate(ns):
        if all(fast[m] < slow[m] for m in ns[i:]):
            return n
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("json")
    ap.add_argument("-o", "--out", default=".")
    args = ap.parse_args()
    series, ctx = load(args.json)
    os.makedirs(args.out, exist_ok=True)

    with open(os.path.join(args.out, "bench.csv"), "w") as f:
        f.write("benchmark,N,ns_per_call\n")
        for name in sorted(series):
            for n in sorted(series[name]):
                f.write(f"{name},{n},{series[name][n]:.1f}\n")

    lines = [f"# soadyn benchmarks ({ctx.get('date', '')}, {ctx.get('num_cpus', '?')} CPUs, "
             f"{ctx.get('mhz_per_cpu', '?')} MHz)", "",
             "## Time per call [ns] and growth exponent over N = 16..256", ""]
    for group in ("chain", "tree", "peer/soadyn", "peer/mujoco"):
        names = sorted(n for n in series if n.startswith(group + "/") and n.count("/") == group.count("/") + 1)
        if not names:
            continue
        ns = sorted(set().union(*(series[n].keys() for n in names)))
        lines.append("| " + group + " | " + " | ".join(f"N={n}" for n in ns) + " | exponent |")
        lines.append("|---" * (len(ns) + 2) + "|")
        for name in names:
            row = [f"{series[name][n]:.0f}" if n in series[name] else "" for n in ns]
            lines.append(f"| {name.split('/')[-1]} | " + " | ".join(row) + f" | {exponent(series[name], 15, 256):.2f} |")
        lines.append("")

    if "peer/mujoco/mass" in series:
        lines += ["## soadyn / MuJoCo (same run, same URDF chains)", ""]
        ns = sorted(series["peer/mujoco/mass"])
        lines.append("| quantity | " + " | ".join(f"N={n}" for n in ns) + " |")
        lines.append("|---" * (len(ns) + 1) + "|")
        for q in ("mass", "bias", "rhs"):
            s, m = series[f"peer/soadyn/{q}"], series[f"peer/mujoco/{q}"]
            lines.append(f"| {q} | " + " | ".join(f"{s[n] / m[n]:.2f}" for n in ns) + " |")
        lines.append("")

    lines += ["## Crossovers", ""]
    for group in ("chain", "tree"):
        if f"{group}/rhs_on" in series:
            lines.append(f"- {group}: O(N) route faster than dense from N = {crossover(series[group + '/rhs_on'], series[group + '/rhs_dense'])}, "
                         f"than tree-sparse from N = {crossover(series[group + '/rhs_on'], series[group + '/rhs_sparse'])}")
    lines.append("")
    with open(os.path.join(args.out, "bench.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))

    fig, ax = plt.subplots(1, 2, figsize=(12, 4.8))
    styles = {"mass_composite": "C0", "mass_literal": "C5", "bias": "C1", "rhs_on": "C2", "rhs_dense": "C3",
              "rhs_sparse": "C4"}
    for a, group in zip(ax, ("chain", "tree")):
        for q, c in styles.items():
            s = series.get(f"{group}/{q}")
            if s:
                ns = sorted(s)
                a.loglog(ns, [s[n] for n in ns], "o-", color=c, ms=3, label=f"soadyn {q} (p={exponent(s, 15, 256):.2f})")
        if group == "chain":
            for q, c in (("mass", "C0"), ("bias", "C1"), ("rhs", "C2")):
                s = series.get(f"peer/mujoco/{q}")
                if s:
                    ns = sorted(s)
                    a.loglog(ns, [s[n] for n in ns], "x--", color=c, label=f"MuJoCo {q} (p={exponent(s):.2f})")
        a.set_title(f"{group}: time per call")
        a.set_xlabel("N bodies")
        a.set_ylabel("ns")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "bench.png"), dpi=90)


if __name__ == "__main__":
    main()
