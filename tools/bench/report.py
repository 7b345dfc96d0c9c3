#!/usr/bin/python3
"""Turn a Google Benchmark JSON of soadyn_bench into bench.csv, bench.md (exponents, ratios,
crossovers) and bench.png (log-log time against N); with --keep, also a JSON of the figures used:
each benchmark's fastest repetition."""
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
    counters = collections.defaultdict(dict)  # "peer/chain/mass/rbdl" -> {N: {"dM": ..}}
    skipped = []  # error messages (a peer that disagreed or could not load a model, a step that failed)
    failed = collections.defaultdict(set)  # "chain/step_symplectic_euler" -> {N}: cases that could not run
    fastest = {}  # benchmark name -> its fastest repetition's entry
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    repetitions = 1
    for b in data["benchmarks"]:
        if b.get("error_occurred"):
            skipped.append(b.get("error_message", b["name"]))
            name, _, n = b["name"].partition("/repeats")[0].rpartition("/")
            if n.isdigit():
                failed[name].add(int(n))
            continue
        if b.get("run_type", "iteration") != "iteration":
            continue
        name, n = b["name"].rsplit("/", 1)
        # with --benchmark_repetitions each benchmark appears once per repetition (interleaved at
        # random with the others): keep the fastest, the one least disturbed by the shared machine
        t = b["real_time"] * scale[b.get("time_unit", "ns")]
        if t <= series[name].get(int(n), t):
            series[name][int(n)] = t
            fastest[b["name"]] = b
        counters[name][int(n)] = {k: b[k] for k in ("dM", "dC", "dqdd") if k in b}
        repetitions = max(repetitions, int(b.get("repetitions", 1)))
    context = dict(data.get("context", {}), repetitions=repetitions)
    kept = {"context": context, "benchmarks": list(fastest.values()) +
            [b for b in data["benchmarks"] if b.get("error_occurred")]}
    return series, counters, skipped, dict(context, failed=failed), kept


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


QUANTITIES = (("mass", "𝓜 (soadyn: mass_matrix(q), from q alone)"), ("bias", "bias C(q, v) (soadyn: bias_forces(q, v), from q and v alone)"), ("rhs", "O(N) forward dynamics (MuJoCo: mj_forward, dense)"))


def peer_series(series, shape, q):
    """{peer name: {N: ns}} for one shape and quantity, soadyn excluded"""
    prefix = f"peer/{shape}/{q}/"
    return {k[len(prefix):]: v for k, v in series.items() if k.startswith(prefix) and k != prefix + "soadyn"}


def best_peer(series, shape, q):
    """{N: (ns, peer name)}: the fastest peer at each N"""
    peers = peer_series(series, shape, q)
    ns = sorted(set().union(*(p.keys() for p in peers.values()))) if peers else []
    return {n: min((p[n], name) for name, p in peers.items() if n in p) for n in ns}


def peer_lines(series, counters, skipped, ctx):
    """bench.md's section: soadyn against the fastest peer at each N, per quantity and shape"""
    peers = sorted({k.split("/")[3] for k in series if k.startswith("peer/") and k.count("/") == 3} - {"soadyn"})
    if not peers:
        return (["## Peers", "", f"No peer timed. Left out: {ctx.get('peers_left_out', 'none built')}."] +
                [f"Not timed: {msg}." for msg in sorted(set(skipped))] + [""])
    lines = ["## soadyn against the fastest peer (same run, same URDF models, same state)", "",
             "Peers: " + ", ".join(f"{p} = {ctx[f'peer_{p}']}" for p in peers if f"peer_{p}" in ctx) + "."]
    if ctx.get("peers_left_out"):
        lines.append(f"Left out: {ctx['peers_left_out']}.")
    worst = {}
    for name, per_n in counters.items():
        lib = name.split("/")[-1]
        for c in per_n.values():
            for k, x in c.items():
                worst[(lib, k)] = max(worst.get((lib, k), 0.0), x)
    if worst:
        lines.append("Checked against soadyn on every model before timing (largest relative 𝓜 and bias "
                     "difference, q̈ backward error): " + "; ".join(
                         f"{p} {worst.get((p, 'dM'), float('nan')):.0e}, {worst.get((p, 'dC'), float('nan')):.0e}, "
                         f"{worst.get((p, 'dqdd'), float('nan')):.0e}" for p in peers) + ".")
    for msg in sorted(set(skipped)):
        lines.append(f"Not timed: {msg}.")
    lines.append("")
    for q, title in QUANTITIES:
        lines += [f"### {title}: ns per call, soadyn / fastest peer", "",
                  "| model | soadyn | fastest peer | peer | soadyn / fastest | " + " | ".join(peers) + " |",
                  "|---" * (5 + len(peers)) + "|"]
        for shape in ("chain", "tree"):
            s = series.get(f"peer/{shape}/{q}/soadyn", {})
            best = best_peer(series, shape, q)
            for n in sorted(set(s) & set(best)):
                b, who = best[n]
                each = [series.get(f"peer/{shape}/{q}/{p}", {}).get(n) for p in peers]
                lines.append(f"| {shape} N={n} | {s[n]:.0f} | {b:.0f} | {who} | {s[n] / b:.2f} | " +
                             " | ".join("" if x is None else f"{x:.0f}" for x in each) + " |")
        lines.append("")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("json")
    ap.add_argument("-o", "--out", default=".")
    ap.add_argument("--keep", help="write the figures used (each benchmark's fastest repetition) to this JSON")
    args = ap.parse_args()
    series, counters, skipped, ctx, kept = load(args.json)
    os.makedirs(args.out, exist_ok=True)
    if args.keep:
        with open(args.keep, "w") as f:
            json.dump(kept, f, indent=1)

    with open(os.path.join(args.out, "bench.csv"), "w") as f:
        f.write("benchmark,N,ns_per_call\n")
        for name in sorted(series):
            for n in sorted(series[name]):
                f.write(f"{name},{n},{series[name][n]:.1f}\n")

    reps = ctx.get("repetitions", 1)
    lines = [f"# soadyn benchmarks ({ctx.get('date', '')}, {ctx.get('num_cpus', '?')} CPUs, "
             f"{ctx.get('mhz_per_cpu', '?')} MHz)", "",
             f"One run; each figure is the fastest of {reps} repetitions, interleaved at random with every other "
             "benchmark of the run." if reps > 1 else "One run, one repetition of each benchmark.", "",
             "## Time per call [ns] and growth exponent over N = 16..256", ""]
    for group in ("chain", "tree"):
        failed = ctx["failed"]  # a case that could not run: "failed" in its cell, the reason under Peers
        names = sorted(n for n in set(series) | set(failed) if n.startswith(group + "/") and n.count("/") == group.count("/") + 1)
        if not names:
            continue
        ns = sorted(set().union(*(set(series.get(n, {})) | failed.get(n, set()) for n in names)))
        lines.append("| " + group + " | " + " | ".join(f"N={n}" for n in ns) + " | exponent |")
        lines.append("|---" * (len(ns) + 2) + "|")
        for name in names:
            s = series.get(name, {})
            row = [f"{s[n]:.0f}" if n in s else "failed" if n in failed.get(name, ()) else "" for n in ns]
            lines.append(f"| {name.split('/')[-1]} | " + " | ".join(row) + f" | {exponent(s, 15, 256):.2f} |")
        lines.append("")

    lines += peer_lines(series, counters, skipped, ctx)

    lines += ["## Crossovers", ""]
    for group in ("chain", "tree"):
        if f"{group}/rhs_on" in series:
            lines.append(f"- {group}: O(N) route faster than dense from N = {crossover(series[group + '/rhs_on'], series[group + '/rhs_dense'])}, "
                         f"than tree-sparse from N = {crossover(series[group + '/rhs_on'], series[group + '/rhs_sparse'])}")
        # prescribed motion: the hybrid dynamics against forward dynamics on the same model, per N
        for part in ("quarter", "half"):
            h, on = series.get(f"{group}/rhs_hybrid_{part}", {}), series.get(f"{group}/rhs_on", {})
            ratios = [h[n] / on[n] for n in sorted(set(h) & set(on)) if on[n] > 0]
            if ratios:
                lines.append(f"- {group}: hybrid dynamics with a {part} of the joints prescribed, "
                             f"{min(ratios):.2f}–{max(ratios):.2f} of the O(N) forward dynamics' time (rhs_on)")
        # closed loops: the chain closed by a point loop at its tip against the open chain, per N
        h, on = series.get(f"{group}/rhs_loop_tip", {}), series.get(f"{group}/rhs_on", {})
        ratios = {n: h[n] / on[n] for n in sorted(set(h) & set(on)) if on[n] > 0}
        if ratios:
            lines.append(f"- {group}: closed by one point loop at the tip (3 rows), " +
                         ", ".join(f"N={n} {r:.2f}" for n, r in ratios.items()) + " × the open tree's forward dynamics (rhs_on)")
    # the closed-loop scenes: constrained forward dynamics against the same tree without its loops
    scenes = [("four_bar", "four-bar (1 hinge loop, 5 rows)"), ("delta", "Delta robot (3 point loops, 9 rows)")]
    rows = []
    for key, title in scenes:
        tree, closed = series.get(f"loops/{key}_tree", {}), series.get(f"loops/{key}_closed", {})
        dense, inverse = series.get(f"loops/{key}_dense", {}), series.get(f"loops/{key}_inverse", {})
        for n in sorted(set(tree) & set(closed)):
            extra = [f"{d[n]:.0f}" if n in d else "" for d in (dense, inverse)]
            rows.append(f"| {title} | {n} | {tree[n]:.0f} | {closed[n]:.0f} | {closed[n] / tree[n]:.2f} | "
                        f"{extra[0]} | {extra[1]} |")
    if rows:
        lines += ["", "## Closed loops: ns per right-hand side", "",
                  "| scene | bodies | tree alone | with its loops | ratio | dense saddle point | constrained inverse dynamics |",
                  "|---|---|---|---|---|---|---|"] + rows
    lines.append("")
    with open(os.path.join(args.out, "bench.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))

    fig, ax = plt.subplots(1, 2, figsize=(12, 4.8))
    styles = {"mass_composite": "C0", "mass_q": "C6", "mass_literal": "C5", "bias": "C1", "bias_qv": "C7",
              "rhs_on": "C2", "rhs_dense": "C3", "rhs_sparse": "C4"}
    for a, group in zip(ax, ("chain", "tree")):
        for q, c in styles.items():
            s = series.get(f"{group}/{q}")
            if s:
                ns = sorted(s)
                a.loglog(ns, [s[n] for n in ns], "o-", color=c, ms=3, label=f"soadyn {q} (p={exponent(s, 15, 256):.2f})")
        for q, c in (("mass", "C0"), ("bias", "C1"), ("rhs", "C2")):
            best = best_peer(series, group, q)
            if best:
                ns = sorted(best)
                a.loglog(ns, [best[n][0] for n in ns], "x--", color=c,
                         label=f"fastest peer {q} ({', '.join(sorted({best[n][1] for n in ns}))})")
        a.set_title(f"{group}: time per call")
        a.set_xlabel("N bodies")
        a.set_ylabel("ns")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "bench.png"), dpi=90)


if __name__ == "__main__":
    main()
