#!/usr/bin/python3
"""The data behind the chart tools' figures, checked against the run files, against runs made
here, and against what the physics says (ctest: tool_plot, tool_work_precision, tool_stability,
tool_crossover).

    check_tools.py plot RUN.h5 EXACT.csv BINNED.csv JOINTS.csv JOINT FIG.svg
                                                  curves tools/plot.py drew (its --data dumps: all
                                                  rows, --bins 20, --joints JOINT) and its SVG
    check_tools.py work_precision DIR T_END       DIR/wp_*.csv from tools/work_precision.py
    check_tools.py stability DIR T_END            DIR/stability.{csv,md} from tools/stability.py
    check_tools.py crossover DIR                  DIR/crossover.{csv,md} from tools/crossover.py --quick
"""
import csv
import math
import re
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


def curves(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], float).reshape(len(rows) - 1, len(rows[0]))
    return {name: data[:, k] for k, name in enumerate(rows[0])}


def rotation_vectors(quat):
    """θ·u from the rotation matrix of each unit quaternion (w, x, y, z): another route than plot.py's"""
    w, x, y, z = (quat / np.linalg.norm(quat, axis=1)[:, None]).T
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    theta = np.arccos(np.clip((R[0, 0] + R[1, 1] + R[2, 2] - 1) / 2, -1, 1))
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    with np.errstate(invalid="ignore", divide="ignore"):
        return theta, (axis * theta / (2 * np.sin(theta))).T


def check_plot(run_file, exact_csv, binned_csv, joints_csv, joint, svg):
    """tools/plot.py on one run: every curve drawn point by point against the file's views (not the
    /samples table plot.py reads), the min/max reduction against the exact curves, --joints, and
    the units on the axes of the SVG."""
    c = curves(exact_csv)
    with h5py.File(run_file, "r") as f:
        t, q = f["time"][:], f["q"][:]
        q_names = [n.decode() for n in f["model"].attrs["q_names"]]
        E, T = f["energy/total"][:], f["energy/kinetic"][:]
        W = f["energy/work_inputs"][:] if "work_inputs" in f["energy"] else None
        L = f["energy/impact_loss"][:] if "impact_loss" in f["energy"] else None
        control = f["control"][:] if "control" in f else None
        v_names = [n.decode() for n in f["model"].attrs["v_names"]]
        events = f["events"][:, 0] if "events" in f else np.empty(0)
        lin, ang = f["momentum/linear"][:], f["momentum/angular"][:]
        scenario = f.attrs["scenario_path"].decode()
        units = dict(zip((n.decode() for n in f["samples"].attrs["column_names"]),
                         (u.decode() for u in f["samples"].attrs["column_units"])))
    name = os.path.basename(scenario).split(".")[0]
    expect(np.array_equal(c["t"], t), f"plot {name}: the time axis is not the file's /time")
    quats = {}
    for k, n in enumerate(q_names):
        owner, _, part = n.rpartition(".")
        if part in ("qw", "qx", "qy", "qz"):
            quats.setdefault(owner, []).append(k)
        else:
            expect(np.array_equal(c.get("q." + n, np.nan), q[:, k]), f"plot {name}: curve 'q.{n}' is not /q[:, {k}]")
    for jq, ks in quats.items():
        theta, rv = rotation_vectors(q[:, ks])
        sure = (theta > 1e-3) & (theta < np.pi - 1e-3)  # where the matrix route is well conditioned
        for a, axis in enumerate("xyz"):
            got = c.get(f"rotvec.{jq}.{axis}")
            expect(got is not None and np.allclose(got[sure], rv[sure, a], rtol=0, atol=1e-7),
                   f"plot {name}: rotation vector {axis} of {jq} differs from the rotation matrix's")
        expect(sure.sum() > len(t) // 2 and np.ptp(theta) > 1e-2, f"plot {name}: {jq} barely turns (a vacuous check)")
    if name == "satellite_two_arrays":
        expect(abs(c["q.left"][0] - 0.3) < 1e-15 and abs(c["q.right"][0] + 0.2) < 1e-15,
               "plot: the array angles do not start at the scenario's 0.3 and -0.2")
        expect(np.ptp(c["q.left"]) > 0.05, "plot: the left array did not move (a vacuous run)")
    # the controllers' torques: one curve per DOF, the file's /control columns
    if control is not None:
        for k, n in enumerate(v_names):
            expect(np.array_equal(c.get("control." + n, np.nan), control[:, k]),
                   f"plot {name}: curve 'control.{n}' is not /control[:, {k}]")
        expect(np.ptp(control) > 1e-3, f"plot {name}: the controllers' torques are constant (a vacuous check)")
    # the energy-balance error, recomputed: |E − E0 − W + L| / max(|E0|, max T); small for every scene
    scale = max(abs(E[0]), T.max())
    balance = np.abs(E - E[0] - (W - W[0] if W is not None else 0) + (L - L[0] if L is not None else 0)) / scale
    expect(np.allclose(c["energy error"], np.maximum(balance, 1e-17), rtol=1e-12, atol=0),
           f"plot {name}: the energy curve is not |E - E0 - W + L| / max(|E0|, max T) of the file")
    if name == "arm_control_limits":  # the elbow's impact took energy: the balance closes only with it counted
        expect(L is not None and L[-1] > 1e-2 * scale and len(events) >= 1,
               f"plot {name}: no impact logged (L = {L[-1] if L is not None else None}, {len(events)} events)")
    expect(c["energy error"].max() < 1e-5, f"plot {name}: energy-balance error {c['energy error'].max():.2e}")
    if name == "stiff_arm":  # damped: the balance closes only with the work of the damper counted
        expect(W is not None and np.abs(W).max() > 1e-2 * scale, f"plot {name}: no work logged by the damper")
    free = [j for j in quats if all(f"{j}.{a}" in q_names for a in "xyz")]
    if free:  # a free-floating model: momentum is conserved
        for k, axis in enumerate("xyz"):
            for kind, h in (("angular", ang), ("linear", lin)):
                curve = c.get(f"{kind} momentum change {axis}")
                expect(curve is not None and np.allclose(curve, np.maximum(np.abs(h[:, k] - h[0, k]), 1e-17), rtol=1e-12, atol=0),
                       f"plot {name}: the {kind} momentum curve {axis} is not the file's change")
                expect(curve is not None and curve.max() < 1e-7 * max(np.linalg.norm(h[0]), 1e-300),
                       f"plot {name}: {kind} momentum {axis} changed")
    # min/max per bin: each bin's pair is the min and max of the exact curve over its rows
    b = curves(binned_csv)
    bins = len(b["t"]) // 2
    expect(set(b) == set(c) and len(b["t"]) == 2 * bins and bins < len(t) // 2,
           f"plot {name}: the binned curves are not the exact ones, reduced")
    which = np.clip(((t - t[0]) / (t[-1] - t[0]) * bins).astype(int), 0, bins - 1)
    centres = t[0] + (np.arange(bins) + 0.5) * (t[-1] - t[0]) / bins
    expect(np.allclose(b["t"][0::2], centres, rtol=1e-14, atol=0), f"plot {name}: bins not centred")
    for label in c:
        if label == "t":
            continue
        lo = np.full(bins, np.nan)
        hi = np.full(bins, np.nan)
        np.fmin.at(lo, which, c[label])
        np.fmax.at(hi, which, c[label])
        ok = np.array_equal(b[label][0::2], lo, equal_nan=True) and np.array_equal(b[label][1::2], hi, equal_nan=True)
        expect(ok, f"plot {name}: the binned '{label}' is not the per-bin min and max of the exact curve")
    # --joints: only the chosen joint's curves, each as without it, and the rest unchanged
    j = curves(joints_csv)
    mine = [k for k in c if k == "q." + joint or k.startswith(("q." + joint + ".", "rotvec." + joint + "."))]
    expect(mine and [k for k in j if k.startswith(("q.", "rotvec."))] == mine,
           f"plot {name}: --joints {joint} drew {[k for k in j if k.startswith(('q.', 'rotvec.'))]}, expected {mine}")
    for k in j:
        expect(k in c and np.array_equal(j[k], c[k], equal_nan=True), f"plot {name}: --joints changed curve '{k}'")
    # units on every axis (SVG text kept as text)
    with open(svg, encoding="utf-8") as f:
        text = f.read()
    q_units = {units["q." + n] for n in q_names if not n.rpartition(".")[2].startswith("q")}
    labels = ["t [s]", "max(|E0|, max T) [1]"] + [f"joint {'angle' if u == 'rad' else 'position'} [{u}]" for u in q_units]
    if quats:
        labels.append("rotation vector θ·u [rad]")
    if free:
        labels += ["|linear momentum − initial| [kg m/s]", "|angular momentum − initial| [kg m^2/s]"]
    if control is not None:
        labels += [f"control {'force' if u == 'N' else 'torque'} [{u}]" for u in {units["control." + n] for n in v_names}]
    for label in labels:
        expect(label in text, f"plot {name}: no axis labelled '{label}' in {svg}")
    # a change that is exactly 0 at every row is drawn at the floor and said so in the legend
    if free:
        for kind, h in (("angular", ang), ("linear", lin)):
            for k, axis in enumerate("xyz"):
                zero = bool(np.all(h[:, k] == h[0, k]))
                said = f"{kind} momentum change {axis} (0 at every row)" in text
                expect(said == zero, f"plot {name}: {kind} momentum {axis} is {'' if zero else 'not '}exactly "
                                     f"conserved, but the legend says {'so' if said else 'nothing'}")
    axes = text.count('<g id="axes_')
    expect(axes == len(labels) - 1, f"plot {name}: {axes} axes in {svg}, expected {len(labels) - 1}")
    # the joint limits' events: one group of dashed lines on every panel, as many lines as events
    marks = text.count('<g id="limit-events')
    expect(marks == (axes if len(events) else 0), f"plot {name}: {marks} panels mark the {len(events)} limit events, "
                                                  f"expected {axes if len(events) else 0}")
    if len(events):
        expect(f"joint-limit events ({len(events)})" in text, f"plot {name}: the legend does not count the {len(events)} events")


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
            rows_expected = 0 if runs.refuses(scene, m) else 6 if runs.split(m)[0] == "implicit-midpoint" else 8
            expect(len(by.get(m, [])) == rows_expected, f"wp {scene}: {m}: rows missing")
        # observed order: the log-log slope of error against step, over the points between the
        # reference's accuracy and 10 % (at least three points, else the method is not judged here)
        for m, p in (("euler", 1.0), ("semi-implicit-euler", 1.0), ("symplectic-euler", 1.0), ("rk4", 4.0), ("implicit-midpoint", 2.0),
                     ("implicit-midpoint/simplified", 2.0), ("variational", 2.0)):
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


def bounded(r):
    """the criterion of tools/stability.py, restated: completed, energy balance within ±5 %"""
    if not r["ok"]:
        return False
    return r["E_rel"].max() <= 0.05 and r["E_rel"].min() >= -0.05


def check_stability(out, t_end):
    """tools/stability.py: every cell present, the stiff arm's limits where its fast mode puts them,
    and a few cells re-run here at the step reported and at twice it."""
    rows = read_csv(os.path.join(out, "stability.csv"))
    table = {(r["scenario"], r["method"]): (float(r["max_stable_dt"]), r["beyond"]) for r in rows}
    scenes = ["pendulum_on_cart", "double_pendulum", "tumbling_t_handle", "three_link_arm", "stiff_arm",
              "flexible_satellite"]
    expect(set(table) == {(s, m) for s in scenes for m in runs.FIXED if not runs.refuses(s, m)}, f"stability: cells {sorted(table)}")
    with open(os.path.join(out, "stability.md")) as f:
        md = f.read()
    for s in scenes:
        line = [l for l in md.splitlines()
                if l.startswith(f"| {s} | ") and l.count("|") == len(runs.FIXED) + 2 and "cvode" not in l]
        expect(len(line) == 1 and all(f"{table[(s, m)][0]:.3g} s" in line[0] for m in runs.FIXED if (s, m) in table),
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
    # full Newton keeps the A-stable rule stable where the simplified Newton iteration diverges
    expect(table[("stiff_arm", "implicit-midpoint")][0] >= 10 * table[("stiff_arm", "implicit-midpoint/simplified")][0],
           "stability: stiff_arm: full Newton not 10x beyond the simplified Newton's step")
    for s in scenes[:4]:
        if table[(s, "euler")][0] < 1.0:  # 1 s: the search bound, stable at every step tried
            expect(table[(s, "rk4")][0] > table[(s, "euler")][0], f"stability: {s}: rk4 no more stable than euler")
    # re-run: bounded at the step reported, and the behaviour at twice it as classified
    for s, m in (("double_pendulum", "euler"), ("double_pendulum", "rk4"), ("stiff_arm", "rk4")):
        dt, beyond = table[(s, m)]
        at = runs.run(s, m, t_end=t_end, dt=dt, output_dt=max(dt, 0.01))
        expect(bounded(at), f"stability: {s} {m} not bounded at its reported step {dt:g}")
        twice = runs.run(s, m, t_end=t_end, dt=2 * dt, output_dt=max(2 * dt, 0.01))
        seen = (("Newton fails" if "did not converge" in twice["status"] else "blow-up") if not twice["ok"] else "energy growth" if twice["E_rel"].max() > 0.05 else
                "numerical damping" if twice["E_rel"].min() < -0.05 else "bounded")
        expect(beyond.startswith(seen), f"stability: {s} {m} at {2 * dt:g} s: '{beyond}' reported, '{seen}' seen")


def check_crossover(out):
    """tools/crossover.py --quick: per method, the finer setting's energy error below the coarser's
    (each converges) on the double pendulum; on the satellite, variational holds |ΔL|/L ≤ 1e-10 over
    1000 s at its coarsest step (0.2 s: 5000 steps), where rk4 at 0.2 s does not"""
    with open(os.path.join(out, "crossover.csv")) as f:
        rows = list(csv.DictReader(f))
    by = {}
    for r in rows:
        by.setdefault(r["method"], []).append((float(r["setting"]), float(r["max_energy_error"])))
    expect(set(by) >= {"cvode-adams", "rk4", "implicit-midpoint", "symplectic-euler", "variational"},
           f"crossover: methods {sorted(by)}")
    for m, pts in by.items():
        pts.sort(reverse=True)  # coarse first
        expect(all(b[1] < a[1] for a, b in zip(pts, pts[1:])), f"crossover: {m}'s energy error does not fall: {pts}")
    md = open(os.path.join(out, "crossover.md")).read()
    expect(re.search(r"\| variational \| dt 0\.2 \|", md) is not None, "crossover: variational does not hold 1e-10 at dt 0.2")
    expect(re.search(r"\| rk4 \| dt 0\.2 \|", md) is None, "crossover: rk4 holds 1e-10 at dt 0.2")


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "plot":
        check_plot(*sys.argv[2:8])
    elif what == "work_precision":
        check_work_precision(sys.argv[2], float(sys.argv[3]))
    elif what == "stability":
        check_stability(sys.argv[2], float(sys.argv[3]))
    elif what == "crossover":
        check_crossover(sys.argv[2])
    else:
        sys.exit(__doc__)
    if failures:
        sys.exit(f"{len(failures)} check(s) failed")
    print(f"check_tools.py {what}: all checks passed")
