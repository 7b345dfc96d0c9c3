#!/usr/bin/python3
"""The data behind the chart tools' figures, checked against the run files, against runs made
here, and against what the physics says (ctest: tool_plot, tool_work_precision, tool_stability).

    check_tools.py plot RUN.h5 CURVES.csv         curves tools/plot.py drew (its --data dump)
    check_tools.py work_precision DIR T_END       DIR/wp_*.csv from tools/work_precision.py
    check_tools.py stability DIR T_END            DIR/stability.{csv,md} from tools/stability.py
"""
import csv
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tools"))
import runs  # noqa: E402

failures = []


def expect(ok, message):
    if not ok:
        failures.append(message)
        print("FAIL:", message)


def check_plot(run_file, curves_csv):
    """tools/plot.py on the satellite: every curve against the file and the physics."""
    with open(curves_csv) as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], float)
    c = {name: data[:, k] for k, name in enumerate(header)}
    with h5py.File(run_file, "r") as f:
        t, q = f["time"][:], f["q"][:]
        E, T = f["energy/total"][:], f["energy/kinetic"][:]
        lin, ang = f["momentum/linear"][:], f["momentum/angular"][:]
    expect(np.array_equal(c["t"], t), "plot: the time axis is not the file's /time")
    # q = [bus x, y, z, qw, qx, qy, qz, left, right] (scenarios/satellite_two_arrays.yaml)
    for name, col in (("q left", 7), ("q right", 8), ("q bus.x", 0), ("q bus.y", 1), ("q bus.z", 2)):
        expect(name in c and np.array_equal(c[name], q[:, col]), f"plot: curve '{name}' is not /q[:, {col}]")
    expect(abs(c["q left"][0] - 0.3) < 1e-15 and abs(c["q right"][0] + 0.2) < 1e-15,
           "plot: the array angles do not start at the scenario's 0.3 and -0.2")
    expect(np.ptp(c["q left"]) > 0.05, "plot: the left array did not move (a vacuous run)")
    # energy and momentum are conserved: the plotted errors are recomputed here and must be small
    scale = max(abs(E[0]), T.max())
    expect(np.allclose(c["energy error"], np.maximum(np.abs(E - E[0]) / scale, 1e-17), rtol=1e-12, atol=0),
           "plot: the energy-error curve is not |E - E0| / max(|E0|, max T) of the file")
    expect(c["energy error"].max() < 1e-8, f"plot: energy error {c['energy error'].max():.2e} (rtol 1e-10 run)")
    for k, axis in enumerate("xyz"):
        for kind, h in (("angular", ang), ("linear", lin)):
            curve = c[f"{kind} momentum change {axis}"]
            expect(np.allclose(curve, np.maximum(np.abs(h[:, k] - h[0, k]), 1e-17), rtol=1e-12, atol=0),
                   f"plot: the {kind} momentum curve {axis} is not the file's change")
            expect(curve.max() < 1e-7 * np.linalg.norm(h[0]), f"plot: {kind} momentum {axis} changed by {curve.max():.2e}")


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def number(x):
    return float(x) if x not in ("", None) else float("nan")


def check_work_precision(out, t_end):
    """tools/work_precision.py: the sweep is complete, errors fall with the methods' orders, and one
    point is recomputed here from two runs."""
    for scene in ("pendulum_on_cart", "double_pendulum", "satellite_two_arrays", "three_link_arm"):
        rows = read_csv(os.path.join(out, f"wp_{scene}.csv"))
        by = {}
        for r in rows:
            by.setdefault(r["method"], []).append(r)
        for m in runs.CVODE:
            rs = by.get(m, [])
            expect(len(rs) == 10 and all(r["status"] == "completed" for r in rs), f"wp {scene}: {m}: {len(rs)} rows")
            err = {number(r["rtol"]): number(r["state_error"]) for r in rs}
            expect(err.get(1e-12, 1) < 1e-8, f"wp {scene}: {m} at rtol 1e-12: state error {err.get(1e-12)}")
            expect(err.get(1e-3, 0) > 100 * err.get(1e-10, 1), f"wp {scene}: {m}: error does not fall with rtol: {err}")
            work = {number(r["rtol"]): number(r["rhs_evals"]) for r in rs}
            expect(work.get(1e-12, 0) > work.get(1e-3, 1), f"wp {scene}: {m}: tighter rtol, no more work: {work}")
        for m in runs.FIXED:
            expect(len(by.get(m, [])) == (6 if m == "implicit-midpoint" else 8), f"wp {scene}: {m}: rows missing")
        # observed order: the log-log slope of error against step, over the points between the
        # reference's accuracy and 10 % (at least three points, else the method is not judged here)
        for m, p in (("euler", 1.0), ("symplectic-euler", 1.0), ("rk4", 4.0), ("implicit-midpoint", 2.0)):
            pts = [(number(r["dt"]), number(r["state_error"])) for r in by.get(m, [])]
            pts = [(h, e) for h, e in pts if 1e-10 <= e <= 0.1]
            if len(pts) < 3:
                continue
            order = np.polyfit(np.log(pts)[:, 0], np.log(pts)[:, 1], 1)[0]
            expect(abs(order - p) < 0.2 * p, f"wp {scene}: {m}: observed order {order:.2f}, expected {p:g}")
    # one point recomputed: double pendulum, rk4 at dt = 1e-2, against CVODE Adams at rtol 1e-13
    ref = runs.run("double_pendulum", "cvode-adams", t_end=t_end, rtol=1e-13, output_dt=t_end)
    r = runs.run("double_pendulum", "rk4", t_end=t_end, dt=1e-2, output_dt=t_end)
    mine = float(np.abs(np.concatenate([r["q"] - ref["q"], r["qd"] - ref["qd"]])).max())
    row = [x for x in read_csv(os.path.join(out, "wp_double_pendulum.csv")) if x["method"] == "rk4" and number(x["dt"]) == 1e-2]
    expect(len(row) == 1 and abs(number(row[0]["state_error"]) - mine) <= 2e-3 * mine,
           f"wp: rk4 dt 1e-2 state error {row[0]['state_error'] if row else '?'} in the CSV, {mine:.3e} recomputed")


def bounded(r, dissipative):
    """the criterion of tools/stability.py, restated: completed, energy within 5 % (above only if damped)"""
    if not r["ok"]:
        return False
    return r["E_rel"].max() <= 0.05 and (dissipative or r["E_rel"].min() >= -0.05)


def check_stability(out, t_end):
    """tools/stability.py: every cell present, the stiff arm's limits where its fast mode puts them,
    and a few cells re-run here at the step reported and at twice it."""
    rows = read_csv(os.path.join(out, "stability.csv"))
    table = {(r["scenario"], r["method"]): (float(r["max_stable_dt"]), r["beyond"]) for r in rows}
    scenes = ["pendulum_on_cart", "double_pendulum", "satellite_two_arrays", "three_link_arm", "stiff_arm"]
    expect(set(table) == {(s, m) for s in scenes for m in runs.FIXED}, f"stability: cells {sorted(table)}")
    with open(os.path.join(out, "stability.md")) as f:
        md = f.read()
    for s in scenes:
        line = [l for l in md.splitlines() if l.startswith(f"| {s} | ") and l.count("|") == len(runs.FIXED) + 2]
        expect(len(line) == 1 and all(f"{table[(s, m)][0]:.3g} s" in line[0] for m in runs.FIXED),
               f"stability: the table row of {s} does not show the CSV's steps")
    # the stiff arm's fast mode (time constant ~0.1 ms) limits the explicit methods to steps of
    # order 1e-4 s (well below the 1 ms at which test_stability sees RK4 blow up); the A-stable
    # implicit midpoint rule is not limited by it
    for m in ("euler", "rk4"):
        dt = table[("stiff_arm", m)][0]
        expect(1e-5 < dt < 1e-3, f"stability: stiff_arm {m}: largest stable step {dt:g} s")
    # on a fast decaying mode (real eigenvalue −λ) explicit Euler is stable for h λ ≤ 2, RK4 for
    # h λ ≤ 2.785: their limits stand in that ratio; the A-stable implicit midpoint rule goes far beyond
    ratio = table[("stiff_arm", "rk4")][0] / table[("stiff_arm", "euler")][0]
    expect(abs(ratio - 2.785 / 2) < 0.15, f"stability: stiff_arm: rk4 / euler largest steps {ratio:.3f}, expected 1.39")
    expect(table[("stiff_arm", "implicit-midpoint")][0] > 20 * table[("stiff_arm", "rk4")][0],
           "stability: stiff_arm: the implicit midpoint rule no more stable than rk4")
    for s in scenes[:4]:
        if table[(s, "euler")][0] < 1.0:  # 1 s: the search bound, stable at every step tried
            expect(table[(s, "rk4")][0] > table[(s, "euler")][0], f"stability: {s}: rk4 no more stable than euler")
    # re-run: bounded at the step reported, and the behaviour at twice it as classified
    for s, m in (("double_pendulum", "euler"), ("double_pendulum", "rk4"), ("stiff_arm", "rk4")):
        dt, beyond = table[(s, m)]
        at = runs.run(s, m, t_end=t_end, dt=dt, output_dt=max(dt, 0.01))
        expect(bounded(at, s == "stiff_arm"), f"stability: {s} {m} not bounded at its reported step {dt:g}")
        twice = runs.run(s, m, t_end=t_end, dt=2 * dt, output_dt=max(2 * dt, 0.01))
        seen = ("blow-up" if not twice["ok"] else "energy growth" if twice["E_rel"].max() > 0.05 else
                "numerical damping" if twice["E_rel"].min() < -0.05 else "bounded")
        expect(beyond.startswith(seen), f"stability: {s} {m} at {2 * dt:g} s: '{beyond}' reported, '{seen}' seen")


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "plot":
        check_plot(sys.argv[2], sys.argv[3])
    elif what == "work_precision":
        check_work_precision(sys.argv[2], float(sys.argv[3]))
    elif what == "stability":
        check_stability(sys.argv[2], float(sys.argv[3]))
    else:
        sys.exit(__doc__)
    if failures:
        sys.exit(f"{len(failures)} check(s) failed")
    print(f"check_tools.py {what}: all checks passed")
