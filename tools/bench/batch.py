#!/usr/bin/python3
"""States per second for q̈ and ∂q̈ over K states: the C++ loop, soadyn::batch from C++ and
soadyn.batch from Python, on 1 and 2 threads.  Not a test: a benchmark.

    tools/bench/batch.py [--build build] [--min-seconds 0.1] [--K 1,10,100,1000,10000,100000]

Models: the 7-DOF arm (tests/data/arm7.urdf, base welded) and the 18-DOF free-floating quadruped
of tools/bench/make_models.py (a free root and 12 revolute joints).  q̈ is forward_dynamics by the
O(N) route; ∂q̈ is forward_dynamics_derivatives (∂q̈/∂q, ∂q̈/∂v; 𝓜⁻¹ not formed: fd_derivatives
with minv=False).  The C++ side is build/soadyn_bench_batch (the loop on one Data; batch with a
Pool kept across calls); the Python side calls a soadyn.batch.Pool kept across calls likewise,
which converts and checks its arguments and allocates its result arrays on every call (the module
functions, soadyn.batch.forward_dynamics(model, …), also make the Pool's Data each call: ~5 µs
more).  Threads start only for a batch worth it (batch.hpp, kWorthAThread).  Each figure is the
best of three windows of at least --min-seconds.  Prints a Markdown table.

The last column is the machine's own 2-thread ceiling at that moment: soadyn_bench_batch's control
loop (independent multiply-add chains in registers: no memory traffic, nothing shared), its fixed
work on one std::thread against split over two, timed right after that K's rows.  The one after
it: the process's CPU time per state of the C++ batch on 2 threads over 1 thread, which the share
of the CPUs the scheduler gives does not change: above 1, running on 2 threads costs work
(cache lines moved between the threads, waiting, thread starts).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def rate(K, min_seconds, f):
    best = 0.0
    for _ in range(3):
        reps, t0 = 0, time.perf_counter()
        while True:
            f()
            reps += 1
            elapsed = time.perf_counter() - t0
            if elapsed >= min_seconds:
                break
        best = max(best, K * reps / elapsed)
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--min-seconds", type=float, default=0.1)
    ap.add_argument("--K", default="1,10,100,1000,10000,100000")
    args = ap.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import numpy as np
    import soadyn

    Ks = [int(k) for k in args.K.split(",")]
    folder = tempfile.mkdtemp(prefix="soadyn_bench_batch_")
    subprocess.run([sys.executable, os.path.join(ROOT, "tools", "bench", "make_models.py"), folder], check=True,
                   stdout=subprocess.DEVNULL)
    models = [("arm7.urdf", os.path.join(ROOT, "tests", "data", "arm7.urdf"), False, "7-DOF arm"),
              ("quadruped_18.urdf", os.path.join(folder, "quadruped_18.urdf"), True, "18-DOF free-floating quadruped")]
    rows = {}  # (model, what, K) -> {how: states/s}
    control = {}  # (model, K) -> {"1 thread": rounds/s, "2 threads": rounds/s}
    cpu = {}  # (model, what, K, how) -> the process's CPU seconds per state (C++ rows)
    for key, path, free, _ in models:
        model = soadyn.load(path, free_root=free)
        rng = np.random.default_rng(5)
        for K in Ks:
            # each K's C++ rows (and the control) right before its Python rows: a shared machine's
            # load changes by the minute, and the ratios compare figures taken seconds apart
            out = subprocess.run([os.path.join(args.build, "soadyn_bench_batch"), path, str(int(free)),
                                  str(args.min_seconds), str(K)], check=True, capture_output=True, text=True).stdout
            for line in out.splitlines():
                r = json.loads(line)
                if r["model"] == "control":  # the machine's own 2-thread ceiling, measured beside this K's rows
                    control[(key, r["K"])] = control.get((key, r["K"]), {}) | {r["how"]: r["states_per_second"]}
                else:
                    rows.setdefault((r["model"], r["what"], r["K"]), {})[r["how"]] = r["states_per_second"]
                    cpu[(r["model"], r["what"], r["K"], r["how"])] = r["cpu_seconds_per_state"]
            q = np.array([model.normalize(rng.uniform(-1, 1, model.nq)) for _ in range(K)])
            v = rng.uniform(-1, 1, (K, model.nv))
            tau = rng.uniform(-3, 3, (K, model.nv))
            for threads in (1, 2):
                how = f"Python batch, {threads} thread" + ("s" if threads > 1 else "")
                pool = soadyn.batch.Pool(model, threads=threads)
                rows[(key, "qdd", K)][how] = rate(K, args.min_seconds, lambda: pool.forward_dynamics(q, v, tau))
                rows[(key, "dqdd", K)][how] = rate(K, args.min_seconds, lambda: pool.forward_dynamics_derivatives(q, v, tau, minv=False))
    hows = ["C++ loop", "C++ batch, 1 thread", "C++ batch, 2 threads", "Python batch, 1 thread", "Python batch, 2 threads"]
    print(f"load average at the end: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print("| model | | K | " + " | ".join(hows) + " | Python 1 t / C++ loop | 2 t / 1 t (C++) | 2 t / 1 t (control) | "
          "CPU per state 2 t / 1 t (C++) |")
    print("|---|---|---:|" + "---:|" * (len(hows) + 4))
    for key, _, _, label in models:
        for what in ("qdd", "dqdd"):
            for K in Ks:
                r, c = rows[(key, what, K)], control[(key, K)]
                cells = " | ".join(f"{r[h]:,.0f}" for h in hows)
                print(f"| {label} | {'q̈' if what == 'qdd' else '∂q̈'} | {K:,} | {cells} | "
                      f"{r['Python batch, 1 thread'] / r['C++ loop']:.2f} | "
                      f"{r['C++ batch, 2 threads'] / r['C++ batch, 1 thread']:.2f} | "
                      f"{c['2 threads'] / c['1 thread']:.2f} | "
                      f"{cpu[(key, what, K, 'C++ batch, 2 threads')] / cpu[(key, what, K, 'C++ batch, 1 thread')]:.2f} |")


if __name__ == "__main__":
    main()
