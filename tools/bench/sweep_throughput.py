#!/usr/bin/env python3
"""Sweep throughput: many short runs, as a plain loop of soadyn.simulate, as `soadyn.sweep` in this
process (the per-case overhead of building each case's scenario and its row), and on an embedded
Dask LocalCluster of 1 and 2 worker processes (the scaling).

    PYTHONPATH=build/python /usr/bin/python3 tools/bench/sweep_throughput.py [--cases 10000]

Each case: the double pendulum, rk4 at dt = 1e-2 for 0.2 s (20 steps) from a random initial state.
Prints a markdown table; the cluster's start (its processes up, soadyn imported in each worker) is
timed apart and not in the walls: the walls are the throughput of a running cluster.
"""
import argparse
import os
import shutil
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "build", "python"))
import soadyn  # noqa: E402

SWEEP = """\
scenario: {root}/scenarios/double_pendulum.yaml
seed: 3
set: {{simulation.method: rk4, simulation.dt: 1.0e-2, simulation.t_end: 0.2, simulation.output_dt: 0.1}}
vary:
  - zip:
      - {{path: initial.q.theta1, uniform: [-2.0, 2.0], count: {n}}}
      - {{path: initial.q.theta2, uniform: [-2.0, 2.0], count: {n}}}
"""


def _warm():
    import soadyn  # noqa: F401  (numpy, yaml and the extension module come with it)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=10000)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="soadyn-sweep-bench-")
    try:
        path = os.path.join(tmp, "bench.sweep.yaml")
        with open(path, "w") as f:
            f.write(SWEEP.format(root=ROOT, n=a.cases))
        sw = soadyn.load_sweep(path)
        n = len(sw.cases)
        # the runs alone: scenarios built beforehand, a loop of simulate
        scenes = [sw.scenario(c) for c in sw.cases]
        t0 = time.perf_counter()
        for s in scenes:
            soadyn.simulate(s)
        bare = time.perf_counter() - t0
        rows = [("plain loop of simulate (scenarios prebuilt)", bare, None)]
        t0 = time.perf_counter()
        soadyn.sweep(sw, os.path.join(tmp, "serial"), scheduler="serial", quiet=True)
        serial = time.perf_counter() - t0
        rows.append(("soadyn.sweep, serial, this process", serial, None))
        from distributed import Client, LocalCluster
        for w in (1, 2):
            t0 = time.perf_counter()
            import dask
            from soadyn._sweep import QUIET_CLUSTER  # the embedded cluster's settings
            with dask.config.set(QUIET_CLUSTER):
                cluster = LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
            client.run(_warm)  # each worker imports soadyn once: part of the start, as on a long-lived cluster
            start = time.perf_counter() - t0
            t0 = time.perf_counter()
            soadyn.sweep(sw, os.path.join(tmp, f"dask{w}"), scheduler=client, quiet=True)
            wall = time.perf_counter() - t0
            client.close()
            cluster.close()
            rows.append((f"LocalCluster, {w} worker(s)", wall, start))
        print(f"{n} cases on {os.cpu_count()} cores\n")
        print("| how | wall, s | per case, ms | cases/s | cluster start, s |\n|---|---|---|---|---|")
        for name, wall, start in rows:
            print(f"| {name} | {wall:.2f} | {1e3 * wall / n:.3f} | {n / wall:.0f} | {'' if start is None else f'{start:.1f}'} |")
        print(f"\nper-case overhead of the sweep over the bare run: {1e3 * (serial - bare) / n:.3f} ms")
        print(f"scaling 1 -> 2 workers: {rows[2][1] / rows[3][1]:.2f}x; 2 workers vs the serial sweep: {serial / rows[3][1]:.2f}x")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
