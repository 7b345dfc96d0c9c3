#!/usr/bin/python3
"""Per-call overhead of the Python module: the same calls timed from Python and in a C++ loop,
on one model and state (a 7-DOF arm by default), side by side.  Not a test: a benchmark.

    tools/bench/python_overhead.py [--model tests/data/arm7.urdf] [--rounds 100] [--processes 9]

The C++ side is soadyn._soadyn._time_cpp: the library calls the Python functions make
(update_kinematics + mass_matrix; update_kinematics + update_velocities + forward_dynamics, O(N)
route; the same + forward_dynamics_derivatives with 𝓜⁻¹ or inverse_dynamics_derivatives with q̈ = tau;
update_kinematics + minverse) in a C++ loop inside this process.  Python and C++ are timed in adjacent windows of
`--calls` calls, round after round, so both see the same machine state; the table gives the best
window of each side and the median over rounds of (Python − C++) in adjacent windows, which
stays meaningful on a loaded machine.

That median still moves from process to process by more than the overhead's size (the same build
gave −3, 136 and 160 ns for fd_derivatives in three processes): each process lays out its code,
stack and heap anew (address-space randomization), and a 2.5 µs kernel that shares the caches and
branch predictors with the interpreter is faster or slower by tens of ns with the layout.  So the
measurement is repeated in --processes fresh processes and the table gives, per call, the median
over processes and their range: the typical overhead and how far one process strays.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import timeit

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(ROOT, "tests", "data", "arm7.urdf"))
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--calls", type=int, default=2000, help="calls per timed window")
    ap.add_argument("--processes", type=int, default=9, help="fresh processes measured one after the other")
    ap.add_argument("--json", action="store_true", help="one process: print its results as JSON")
    args = ap.parse_args()
    if args.processes < 1 or args.rounds < 1 or args.calls < 1:
        ap.error("--processes, --rounds and --calls take positive counts")
    if args.processes > 1 and not args.json:
        return across_processes(args)
    sys.path.insert(0, os.path.join(args.build, "python"))
    import numpy as np
    import soadyn
    from soadyn import _soadyn

    model = soadyn.load(args.model)
    data = model.create_data()
    q = model.normalize(0.1 * np.arange(model.nq))
    v = 0.05 * np.arange(model.nv)
    tau = 0.2 * np.arange(model.nv) - 0.5
    env = dict(soadyn=soadyn, model=model, data=data, q=q, v=v, tau=tau, qs=np.repeat(q, 2)[::2], ql=list(q))
    calls = [("mass_matrix(model, data, q)", "mass_matrix", "soadyn.mass_matrix(model, data, q)"),
             ("forward_dynamics(model, data, q, v, tau)", "forward_dynamics",
              "soadyn.forward_dynamics(model, data, q, v, tau)"),
             ("forward_dynamics(…, method='aba')", "forward_dynamics",
              "soadyn.forward_dynamics(model, data, q, v, tau, method='aba')"),
             ("fd_derivatives(model, data, q, v, tau)", "fd_derivatives",
              "soadyn.forward_dynamics_derivatives(model, data, q, v, tau)"),
             ("id_derivatives(model, data, q, v, qdd)", "id_derivatives",
              "soadyn.inverse_dynamics_derivatives(model, data, q, v, tau)"),
             ("minverse(model, data, q)", "minverse", "soadyn.minverse(model, data, q)"),
             ("mass_matrix, q strided (q[::2] of a copy)", "mass_matrix", "soadyn.mass_matrix(model, data, qs)"),
             ("mass_matrix, q a Python list", "mass_matrix", "soadyn.mass_matrix(model, data, ql)")]
    n = args.calls
    cpp = {name: [] for name, _, _ in calls}
    py = {name: [] for name, _, _ in calls}
    for _ in range(args.rounds):
        for name, which, stmt in calls:
            cpp[name].append(_soadyn._time_cpp(model, data, q, v, tau, which, n))
            py[name].append(timeit.timeit(stmt, globals=env, number=n) / n * 1e9)
    result = {"model": os.path.relpath(args.model, ROOT), "nq": model.nq, "nv": model.nv,
              "calls": [{"name": name, "cpp": min(cpp[name]), "python": min(py[name]),
                         "adjacent": statistics.median(b - a for a, b in zip(cpp[name], py[name]))}
                        for name, _, _ in calls]}
    if args.json:
        print(json.dumps(result))
        return
    print(f"model {result['model']}: nq = {model.nq}, nv = {model.nv}; {args.rounds} rounds of {n} calls per side")
    print("| call from Python | C++ ns (best) | Python ns (best) | added ns (best) | added ns (median of adjacent) |")
    print("|---|---|---|---|---|")
    for c in result["calls"]:
        print(f"| {c['name']} | {c['cpp']:.0f} | {c['python']:.0f} | {c['python'] - c['cpp']:.0f} | {c['adjacent']:.0f} |")


def across_processes(args):
    """The one-process measurement in args.processes fresh processes, one after the other."""
    runs = []
    for _ in range(args.processes):
        out = subprocess.run([sys.executable, os.path.abspath(__file__), "--json", "--model", args.model,
                              "--build", args.build, "--rounds", str(args.rounds), "--calls", str(args.calls)],
                             check=True, capture_output=True, text=True).stdout
        runs.append(json.loads(out))
    first = runs[0]
    print(f"model {first['model']}: nq = {first['nq']}, nv = {first['nv']}; {args.processes} processes, each "
          f"{args.rounds} rounds of {args.calls} calls per side; median over the processes [lowest, highest]")
    print("| call from Python | C++ ns (best) | Python ns (best) | added ns: median of adjacent windows |")
    print("|---|---|---|---|")
    for k, c in enumerate(first["calls"]):
        cpp = [r["calls"][k]["cpp"] for r in runs]
        py = [r["calls"][k]["python"] for r in runs]
        added = [r["calls"][k]["adjacent"] for r in runs]
        print(f"| {c['name']} | {statistics.median(cpp):.0f} | {statistics.median(py):.0f} | "
              f"{statistics.median(added):.0f} [{min(added):.0f}, {max(added):.0f}] |")


if __name__ == "__main__":
    main()
