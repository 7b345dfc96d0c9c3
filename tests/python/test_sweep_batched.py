"""A sweep task's cases that differ only in their initial state run together (soadyn._batched: one
library call per group): their rows against the same cases run one soadyn.simulate each (run_batch
with together=False), bit for bit but the CPU time; the cases that cannot go together (a value the
parser refuses, a multi-DOF joint's value, a group of one, every case with --keep-logs) run alone."""
import math
import os

import numpy as np
import pytest
import yaml

import soadyn
from conftest import SCENARIOS
from soadyn import _batched
from soadyn.ensemble import RESULT_COLUMNS, case_path, run_batch

COLUMNS = [c for c in RESULT_COLUMNS if c != "cpu_seconds"] + ["case"]


def same_rows(a, b):
    assert [r["case"] for r in a] == [r["case"] for r in b]
    for x, y in zip(a, b):
        assert set(x) == set(y)
        for c in COLUMNS:
            if isinstance(x[c], float):  # the bits: NaN == NaN, -0 != +0
                assert isinstance(y[c], float) and np.float64(x[c]).view(np.int64) == np.float64(y[c]).view(np.int64), (x["case"], c, x[c], y[c])
            else:
                assert type(x[c]) is type(y[c]) and x[c] == y[c], (x["case"], c, x[c], y[c])


def both_ways(scenario, settings, cases, reference=None):
    """(rows together, rows one by one, the case ids that ran together)"""
    path = os.path.join(SCENARIOS, scenario)
    text = open(path).read()
    together = run_batch(text, path, settings, cases, reference)
    alone = run_batch(text, path, settings, cases, reference, together=False)
    tree = yaml.safe_load(text)
    model = soadyn.parse_scenario(text, case_path(path)).model
    grouped = _batched.run_together(tree, model, path, [(i, dict(settings, **v)) for i, v in cases], reference, {})
    return together, alone, sorted(grouped)


def test_double_pendulum_rows_bit_for_bit():
    """two methods × 9 initial states (by name and by index, q and qd, ints, tiny, -0.0, the parser's
    bound) against a CVODE reference, and cases that run alone: values the parser refuses (beyond
    its bound, a boolean, text, an int no double holds, NaN), a mass varied (a group of one)"""
    rng = np.random.default_rng(3)
    states = [{"initial.q.theta1": float(a), "initial.q[1]": float(b), "initial.qd.theta2": float(c)}
              for a, b, c in rng.uniform(-2, 2, (5, 3))]
    states += [{"initial.q.theta1": 1, "initial.q[1]": -2, "initial.qd.theta2": 0},
               {"initial.q.theta1": 1e-05, "initial.q[1]": -0.0, "initial.qd.theta2": 3.0000000000000004},
               {"initial.q.theta1": 1e6, "initial.q[1]": 0.1, "initial.qd.theta2": -7},
               {"initial.q.theta1": -1e-300, "initial.q[1]": 0.5, "initial.qd.theta2": 2.5}]
    alone = [{"initial.q.theta1": 2e6, "initial.q[1]": 0.1, "initial.qd.theta2": 0.0},
             {"initial.q.theta1": True, "initial.q[1]": 0.1, "initial.qd.theta2": 0.0},
             {"initial.q.theta1": "0.5", "initial.q[1]": 0.1, "initial.qd.theta2": 0.0},
             {"initial.q.theta1": 2 ** 1100, "initial.q[1]": 0.1, "initial.qd.theta2": math.nan}]
    cases = []
    for method in ("rk4", "cvode-adams"):
        for values in states + alone:
            cases.append((len(cases), dict(values, **{"simulation.method": method})))
    cases.append((len(cases), {"initial.q.theta1": 0.3, "initial.q[1]": 0.2, "initial.qd.theta2": 0.1,
                               "simulation.method": "rk4", "bodies.upper.mass": 2.0}))
    settings = {"simulation.t_end": 0.3, "simulation.output_dt": 0.05, "simulation.dt": 0.01}
    together, one_by_one, grouped = both_ways("double_pendulum.yaml", settings, cases,
                                              {"method": "cvode-adams", "rtol": 1e-10, "atol": 1e-12})
    same_rows(together, one_by_one)
    expected = [i for i, v in cases if v in [dict(s, **{"simulation.method": m}) for s in states for m in ("rk4", "cvode-adams")]]
    assert grouped == expected and len(grouped) == 18
    by_case = {r["case"]: r for r in together}
    assert all(by_case[i]["completed"] and math.isfinite(by_case[i]["state_error"]) for i in grouped)
    # the parser's refusals, from the runs alone
    assert by_case[9]["status"].startswith("refused: ")
    assert by_case[10]["status"].startswith("refused: ")


def test_limits_and_controllers_refusals_per_run():
    """the two-link arm under sampled PD control with enforced limits (CVODE's events): a start past
    the elbow's limit is refused by that run alone, inside the group"""
    cases = [(k, {"initial.q.elbow": e, "initial.qd.shoulder": w})
             for k, (e, w) in enumerate([(0.5, 0.0), (2.0, 1.0), (2.6, 0.0), (-2.4, -3.0), (2.49, 2.0)])]
    settings = {"simulation.t_end": 0.3}
    together, one_by_one, grouped = both_ways("arm_control_limits.yaml", settings, cases)
    same_rows(together, one_by_one)
    assert grouped == [0, 1, 2, 3, 4]
    assert together[2]["status"].startswith("refused: ") and not together[0]["status"].startswith("refused")


def test_multi_dof_values_run_alone():
    """a ball joint's initial values (a quaternion, an angular velocity) are the parser's to read"""
    path = os.path.join(SCENARIOS, "spherical_pendulum.yaml")
    model = soadyn.load_scenario(path).model
    v = list(model.v_names)
    cases = [(k, {f"initial.qd[{i}]": float(x) for i, x in enumerate(w)})
             for k, w in enumerate(np.random.default_rng(1).uniform(-1, 1, (3, len(v))))]
    together, one_by_one, grouped = both_ways("spherical_pendulum.yaml", {"simulation.t_end": 0.2}, cases)
    same_rows(together, one_by_one)
    assert grouped == []


def test_sweep_keep_logs_runs_alone_with_the_same_table(tmp_path):
    """soadyn.sweep with keep_logs runs each case alone (its log): the same table as the batched sweep"""
    sweep = tmp_path / "dp.sweep.yaml"
    sweep.write_text(f"""\
scenario: {SCENARIOS}/double_pendulum.yaml
seed: 2
set: {{simulation.t_end: 0.2, simulation.output_dt: 0.05, simulation.method: rk4, simulation.dt: 0.01}}
vary:
  - zip:
      - {{path: initial.q.theta1, uniform: [-2.0, 2.0], count: 6}}
      - {{path: initial.qd.theta2, uniform: [-1.0, 1.0], count: 6}}
""")
    a = soadyn.sweep(str(sweep), str(tmp_path / "a"), scheduler="serial", quiet=True)
    b = soadyn.sweep(str(sweep), str(tmp_path / "b"), scheduler="serial", quiet=True, keep_logs=True)
    assert sorted(os.listdir(tmp_path / "b" / "logs")) == [f"case-{i:07d}.h5" for i in range(6)]
    assert not os.path.exists(tmp_path / "a" / "logs")
    for c in a.table:
        if c == "cpu_seconds":
            continue
        x, y = a.table[c], b.table[c]
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.int64), y.view(np.int64)), c
        else:
            assert list(x) == list(y), c
    traj = soadyn.read_log(str(tmp_path / "b" / "logs" / "case-0000003.h5"))
    assert traj.q[0, 0] == b.table["initial.q.theta1"][3]


def test_shapes_refused():
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    with pytest.raises(soadyn.Error, match=r"q0: expected shape \(K, 2\)"):
        soadyn._soadyn._simulate_states(scene, scene.settings, np.zeros((3, 3)), np.zeros((3, 2)))
    with pytest.raises(soadyn.Error, match=r"v0: expected shape \(3, 2\)"):
        soadyn._soadyn._simulate_states(scene, scene.settings, np.zeros((3, 2)), np.zeros((2, 2)))


def test_ctrl_c_stops_a_batched_task_and_the_sweep_resumes(tmp_path):
    """SIGINT in the middle of a task's batched call ends `soadyn sweep --scheduler serial` within a
    fraction of the task (the call polls Python's signal handlers), writes no part for that task, and
    the same command then runs only the cases left"""
    import signal
    import subprocess
    import time
    from conftest import SOADYN
    sweep = tmp_path / "long.sweep.yaml"
    sweep.write_text(f"""\
scenario: {SCENARIOS}/double_pendulum.yaml
set: {{simulation.t_end: 4.0, simulation.output_dt: 0.5, simulation.method: rk4, simulation.dt: 1.0e-4}}
vary:
  - {{path: initial.q.theta1, uniform: [-2.0, 2.0], count: 120}}
""")
    out = tmp_path / "out"
    t_start = time.monotonic()
    p = subprocess.Popen([SOADYN, "sweep", str(sweep), "-o", str(out), "--scheduler", "serial", "--batch-size", "40", "-q"],
                         stderr=subprocess.PIPE, text=True)
    parts = out / "parts"
    while not (parts.is_dir() and any(n.endswith(".json") for n in os.listdir(parts))):
        assert p.poll() is None and time.monotonic() - t_start < 300, "no task finished"
        time.sleep(0.01)
    first_task = time.monotonic() - t_start  # the process's start and one task of 40 cases
    time.sleep(0.2)
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130 and "sweep interrupted" in err, err
    assert time.monotonic() - t0 < 0.5 * first_task  # not at the end of the task (~0.8 first_task away)
    done = sorted(n for n in os.listdir(parts) if n.endswith(".json"))
    assert 1 <= len(done) < 3
    r = soadyn.sweep(str(sweep), str(out), scheduler="serial", quiet=True)
    assert r.skipped == 40 * len(done) and r.ran == 120 - r.skipped and r.failed == 0


def test_cases_and_batched_import_one_way():
    """_batched builds on _cases (run_batch: the groups here, the rest by run_case); _cases imports
    nothing of _batched, so neither module needs the other half-loaded"""
    import ast
    from soadyn import _cases

    def imported(module):
        tree = ast.parse(open(module.__file__).read())
        return {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module} | \
               {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert "_cases" in imported(_batched) and "_batched" not in imported(_cases)
