#!/usr/bin/python3
"""Per-call overhead of the Python module: the same calls timed from Python and in a C++ loop,
on one model and state (a 7-DOF arm by default), side by side.  Not a test: a benchmark.

    tools/bench/python_overhead.py [--model tests/data/arm7.urdf] [--rounds 200]

The C++ side is soadyn._soadyn._time_cpp: the library calls the Python functions make
(update_kinematics + mass_matrix; update_kinematics + update_velocities + forward_dynamics, O(N)
route; the same + forward_dynamics_derivatives with 𝓜⁻¹ or inverse_dynamics_derivatives with q̈ = tau;
update_kinematics + minverse) in a C++ loop inside this process.  Python and C++ are timed in adjacent windows of
`--calls` calls, round after round, so both see the same machine state; the table gives the best
window of each side and the median over rounds of (Python − C++) in adjacent windows, which
stays meaningful on a loaded machine.
"""
import argparse
import os
import statistics
import sys
import timeit

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(ROOT, "tests", "data", "arm7.urdf"))
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--rounds", type=int, default=200)
    ap.add_argument("--calls", type=int, default=2000, help="calls per timed window")
    args = ap.parse_args()
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
              "soadyn.fd_derivatives(model, data, q, v, tau)"),
             ("id_derivatives(model, data, q, v, qdd)", "id_derivatives",
              "soadyn.id_derivatives(model, data, q, v, tau)"),
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
    print(f"model {os.path.relpath(args.model, ROOT)}: nq = {model.nq}, nv = {model.nv}; "
          f"{args.rounds} rounds of {n} calls per side")
    print("| call from Python | C++ ns (best) | Python ns (best) | added ns (best) | added ns (median of adjacent) |")
    print("|---|---|---|---|---|")
    for name, _, _ in calls:
        c, p = min(cpp[name]), min(py[name])
        med = statistics.median(b - a for a, b in zip(cpp[name], py[name]))
        print(f"| {name} | {c:.0f} | {p:.0f} | {p - c:.0f} | {med:.0f} |")


if __name__ == "__main__":
    main()
