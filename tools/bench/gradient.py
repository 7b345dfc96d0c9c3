#!/usr/bin/python3
"""What a whole run's derivatives cost against one plain run of the same scene and tolerance: the
adjoint gradient (soadyn.gradient: x₀ and all 10·N inertial parameters at once), forward
sensitivities (simulate(sensitivities=…)) for one body's 10 parameters and for x₀, and the
baseline of central differences of whole runs, 2·(10·N + 2·nv) + 1 plain runs.  Not a test: a
benchmark.

    tools/bench/gradient.py [--build build] [--repeat 3] [--t-end 1.0] [--rtol 1e-8] [--processes 3] [--every-body]

Models: the 7-DOF arm (tests/data/arm7.urdf) and the 50-DOF humanoid of tools/humanoid_urdf.py
(fixed root), gravity on, a seeded initial state, CVODE Adams.  The cost tracks a run of the same
robot from another initial state (∫ ½|q − q̂|² + ½·0.1|v − v̂|² dt, soadyn.tracking_cost).  CPU
seconds of the calling thread (time.thread_time), best of --repeat.  The bars of the issue: the
adjoint ≤ 5× a plain run; forward sensitivities for k parameters ≤ (1 + 0.5 k)×.  Prints a
Markdown table; --every-body adds a second: one body's 10 parameters for each body in turn, with
the steps its error control takes against the plain run's.

The measurement runs in --processes fresh processes, one after the other, and each cell is the
median over them: a process's times move with where its stack and heap lie (the same plain run of
the humanoid over 1 s took 42–43 ms in six processes and 49.7 ms in another), and a ratio whose
denominator came from a slow process is no measurement of the method.  The ratios' range over the
processes is given in brackets.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def best(repeat, f):
    out, t = None, float("inf")
    for _ in range(repeat):
        t0 = time.thread_time()
        out = f()
        t = min(t, time.thread_time() - t0)
    return t, out


def measure(args):
    """One process's rows: each model's times (s) and step counts."""
    sys.path.insert(0, os.path.join(args.build, "python"))
    import numpy as np
    import soadyn
    warnings.simplefilter("ignore", RuntimeWarning)  # limits not enforced: the robots swing through them

    settings = dict(method="cvode-adams", rtol=args.rtol, atol=args.rtol * 1e-2, t_end=args.t_end)
    rows = []
    with tempfile.TemporaryDirectory(prefix="soadyn_bench_gradient_") as folder:
        humanoid = os.path.join(folder, "humanoid.urdf")
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "humanoid_urdf.py"), "-o", humanoid], check=True,
                       stdout=subprocess.DEVNULL)
        for name, path in (("7-DOF arm", os.path.join(ROOT, "tests", "data", "arm7.urdf")), ("humanoid", humanoid)):
            scene = soadyn.load_scenario(path)
            model = scene.model
            rng = np.random.default_rng(3)
            lo = np.where(np.isfinite(model.lower), model.lower, -1.0)
            hi = np.where(np.isfinite(model.upper), model.upper, 1.0)
            mid, half = (lo + hi) / 2, (hi - lo) / 2
            scene.q0 = mid + 0.3 * half * rng.uniform(-1, 1, model.nv)
            scene.v0 = 0.3 * rng.uniform(-1, 1, model.nv)
            reference = soadyn.load_scenario(path)
            reference.q0 = mid + 0.3 * half * rng.uniform(-1, 1, model.nv)
            reference.v0 = np.zeros(model.nv)
            ref = soadyn.simulate(reference, output_dt=0.01, **settings)
            cost = soadyn.tracking_cost(model, ref, q=1.0, v=0.1)
            plain, run = best(args.repeat, lambda: soadyn.simulate(scene, output_dt=args.t_end, **settings))
            adj, g = best(args.repeat, lambda: soadyn.gradient(scene, cost, **settings))
            # one body's 10 parameters: the middle body's for the main table, or every body's
            middle = model.body_names[model.nbodies // 2]
            bodies = list(model.body_names) if args.every_body else [middle]
            one_body = {body: best(args.repeat, lambda: soadyn.simulate(scene, output_dt=args.t_end,
                                                                       sensitivities={"parameters": [body]}, **settings))
                        for body in bodies}
            fwd_p, run_p = one_body[middle]
            fwd_x, run_x = best(args.repeat, lambda: soadyn.simulate(scene, output_dt=args.t_end,
                                                                  sensitivities={"initial_state": True}, **settings))
            pi = soadyn.parameters(model)
            rows.append(dict(name=name, nv=model.nv, nbodies=model.nbodies, plain=plain, adjoint=adj, sens_p=fwd_p,
                             sens_x=fwd_x, steps=run.summary.steps, adjoint_steps=[g.stats["forward_steps"],
                                                                                   g.stats["backward_steps"]],
                             steps_p=run_p.summary.steps, steps_x=run_x.summary.steps,
                             bodies=[dict(name=body, mass=pi[10 * b], time=one_body[body][0],
                                          steps=one_body[body][1].summary.steps)
                                     for b, body in enumerate(model.body_names) if args.every_body]))
    return rows


def every_body_table(runs):
    """One body's 10 parameters for each body of each model: the median ratio over the processes."""
    print("\n| model | body | mass (kg) | steps (× plain run's) | forward sens. 10 parameters: ratio (bar 6) |")
    print("|---|---|---|---|---|")
    for k, r in enumerate(runs[0]):
        for j, b in enumerate(r["bodies"]):
            xs = [run[k]["bodies"][j]["time"] / run[k]["plain"] for run in runs]
            print(f"| {r['name']} | {b['name']} | {b['mass']:.3g} | {b['steps'] / r['steps']:.2f} | "
                  f"{statistics.median(xs):.2f} [{min(xs):.2f}, {max(xs):.2f}] |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--processes", type=int, default=3, help="fresh processes measured one after the other")
    ap.add_argument("--every-body", action="store_true", help="also one body's 10 parameters for every body")
    ap.add_argument("--json", action="store_true", help="measure in this process and print its rows as JSON")
    args = ap.parse_args()
    if args.repeat < 1 or args.processes < 1:
        ap.error("--repeat and --processes take positive counts")
    if args.json:
        print(json.dumps(measure(args)))
        return
    runs = []
    for _ in range(args.processes):
        out = subprocess.run([sys.executable, os.path.abspath(__file__), "--json", "--build", args.build,
                              "--repeat", str(args.repeat), "--t-end", repr(args.t_end), "--rtol", repr(args.rtol)]
                             + (["--every-body"] if args.every_body else []),
                             check=True, capture_output=True, text=True).stdout
        runs.append(json.loads(out))
    print(f"CVODE Adams, rtol {args.rtol:g}, t_end {args.t_end:g} s; CPU time of the calling thread, best of "
          f"{args.repeat} in each of {args.processes} processes; the median over the processes [their range]\n")
    print("| model | nv | N | plain run | adjoint: x₀ + 10·N parameters | ratio | forward sens. 10 parameters (k = 10) "
          "| ratio (bar 6) | forward sens. x₀ (k = 2nv) | ratio (bar 1 + nv) | central differences (runs) | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k, r in enumerate(runs[0]):
        rows = [run[k] for run in runs]

        def ms(key):
            return statistics.median(x[key] for x in rows) * 1e3

        def ratio(key):
            xs = [x[key] / x["plain"] for x in rows]
            return f"{statistics.median(xs):.2f} [{min(xs):.2f}, {max(xs):.2f}]"

        calls = 2 * (10 * r["nbodies"] + 2 * r["nv"]) + 1
        fs, bs = r["adjoint_steps"]
        print(f"| {r['name']} | {r['nv']} | {r['nbodies']} | {ms('plain'):.2f} ms ({r['steps']} steps) | "
              f"{ms('adjoint'):.2f} ms ({fs} + {bs} steps) | {ratio('adjoint')} | "
              f"{ms('sens_p'):.2f} ms ({r['steps_p']} steps) | {ratio('sens_p')} | "
              f"{ms('sens_x'):.2f} ms ({r['steps_x']} steps) | {ratio('sens_x')} | "
              f"{calls} × plain = {calls * ms('plain'):.0f} ms | {calls:.0f} |")
    if args.every_body:
        every_body_table(runs)


if __name__ == "__main__":
    main()
