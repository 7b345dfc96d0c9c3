"""Sweeps: the sweep file's cases against scenarios edited by hand, Dask clusters (embedded and real
multi-process) against a plain loop bit for bit, a worker killed mid-sweep, a killed sweep resumed."""
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request

import numpy as np
import pytest

import soadyn
from conftest import SCENARIOS, SOADYN, cli_error

distributed = pytest.importorskip("distributed")

# 2 methods × 2 steps × 12 initial states = 48 runs of 1 s, each against a CVODE reference
SWEEP = """\
scenario: {scenarios}/double_pendulum.yaml
seed: 7
set: {{simulation.t_end: 1.0, simulation.output_dt: 0.05}}
vary:
  - path: simulation.method
    values: [rk4, symplectic-euler]
  - {{path: simulation.dt, grid: [2.0e-3, 1.0e-2], count: 2, scale: log}}
  - zip:
      - {{path: initial.q.theta1, uniform: [-2.0, 2.0], count: 12}}
      - path: initial.q[1]
        normal: [0.0, 0.5]
        count: 12
reference: {{method: cvode-adams, rtol: 1.0e-11, atol: 1.0e-13}}
"""
DETERMINISTIC = [c for c in ("case", "simulation.method", "simulation.dt", "initial.q.theta1", "initial.q[1]", "status",
                             "completed", "initial_energy", "t_reached", "steps", "rhs_evals", "max_energy_balance_error", "final_energy_balance_error",
                             "state_error", "final_state_error", "reference_status")]


def same_tables(a, b):
    """identical, bit for bit, in every column but the CPU time"""
    assert list(a) == list(b)
    for c in DETERMINISTIC:
        x, y = a[c], b[c]
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.int64), y.view(np.int64)), c  # bits: NaN == NaN, -0 != +0
        else:
            assert list(x) == list(y), c


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    p = tmp_path_factory.mktemp("sweep") / "dp.sweep.yaml"
    p.write_text(SWEEP.format(scenarios=SCENARIOS))
    return str(p)


@pytest.fixture(scope="module")
def serial(sweep_file, tmp_path_factory):
    return soadyn.sweep(sweep_file, str(tmp_path_factory.mktemp("serial") / "out"), scheduler="serial", quiet=True)


class Cluster:
    """`dask scheduler` and n `dask worker` processes (no nanny: a killed worker stays dead) on 127.0.0.1"""

    def __init__(self, tmp, n):
        self.file = str(tmp / "scheduler.json")
        env = dict(os.environ, DASK_DISTRIBUTED__LOGGING__DISTRIBUTED="error")
        self.procs = [subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--dashboard-address", ":0",
                                        "--scheduler-file", self.file], stderr=subprocess.DEVNULL, env=env)]
        deadline = time.monotonic() + 60
        while not os.path.exists(self.file):
            assert time.monotonic() < deadline, "the Dask scheduler did not start"
            time.sleep(0.1)
        self.workers = [subprocess.Popen(["dask", "worker", "--scheduler-file", self.file, "--nthreads", "1", "--no-nanny",
                                          "--host", "127.0.0.1"], stderr=subprocess.DEVNULL, env=env) for _ in range(n)]
        self.procs += self.workers
        self.client = distributed.Client(scheduler_file=self.file, timeout="60s")
        self.client.wait_for_workers(n, timeout=60)
        self.address = self.client.scheduler.address

    def close(self):
        self.client.close()
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in self.procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    c = Cluster(tmp_path_factory.mktemp("cluster"), 2)
    yield c
    c.close()


def test_cases_are_the_scenario_edited_by_hand(sweep_file, serial):
    """a plain loop: each case's scenario built by hand from the base, run, and its reference"""
    sw = soadyn.load_sweep(sweep_file)
    assert len(sw.cases) == 48 and sw.paths == ["simulation.method", "simulation.dt", "initial.q.theta1", "initial.q[1]"]
    t = serial.table
    assert list(t["case"]) == list(range(48)) and serial.failed == 0
    base = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    for i in range(0, 48, 5):
        c = sw.cases[i]
        scene = sw.scenario(c)
        assert np.array_equal(scene.model.masses, base.model.masses)
        assert list(scene.q0) == [c["initial.q.theta1"], c["initial.q[1]"]] and list(scene.v0) == [0.0, 0.0]
        assert (scene.settings.method, scene.settings.dt, scene.settings.t_end) == (c["simulation.method"], c["simulation.dt"], 1.0)
        traj = soadyn.simulate(scene)
        ref = soadyn.simulate(scene, "cvode-adams", rtol=1e-11, atol=1e-13)
        y, yr = np.hstack([traj.q, traj.v]), np.hstack([ref.q, ref.v])
        common = np.isin(traj.t, ref.t)
        assert common.sum() >= 2
        assert t["steps"][i] == traj.summary.steps and t["rhs_evals"][i] == traj.summary.rhs_evals
        assert t["max_energy_balance_error"][i] == traj.summary.max_energy_balance_error
        assert t["initial_energy"][i] == traj.total_energy[0]
        assert t["state_error"][i] == np.max(np.abs(y[common] - yr[np.isin(ref.t, traj.t)]))
        assert t["final_state_error"][i] == np.max(np.abs(y[-1] - yr[-1]))
    # the draws: seeded, in range, and the grid as asked
    assert np.all(np.abs(t["initial.q.theta1"]) <= 2.0) and len(set(t["initial.q.theta1"])) == 12
    assert sorted(set(t["simulation.dt"])) == [2e-3, 1e-2]
    assert soadyn.load_sweep(sweep_file).cases == sw.cases
    # rk4 is far more accurate than symplectic Euler at the same step
    rk4, se = t["simulation.method"] == "rk4", t["simulation.method"] == "symplectic-euler"
    assert np.median(t["state_error"][rk4]) < 1e-3 * np.median(t["state_error"][se])
    # the file holds the same table
    same_tables(soadyn.read_results(serial.path), t)


def test_real_cluster_and_embedded_cluster_equal_the_serial_loop(sweep_file, serial, cluster, tmp_path):
    remote = soadyn.sweep(sweep_file, str(tmp_path / "remote"), scheduler=cluster.address, batch_size=5, quiet=True)
    assert remote.ran == 48 and remote.skipped == 0
    same_tables(remote.table, serial.table)
    # the workers did run it: both of them
    assert len(cluster.client.scheduler_info()["workers"]) == 2
    embedded = soadyn.sweep(sweep_file, str(tmp_path / "embedded"), workers=2, quiet=True)
    same_tables(embedded.table, serial.table)
    # the embedded cluster's workers wrote the parts themselves: a second run finds every case there
    again = soadyn.sweep(sweep_file, str(tmp_path / "embedded"), scheduler="serial", quiet=True)
    assert (again.ran, again.skipped) == (0, 48)
    same_tables(again.table, serial.table)


def test_progress_and_the_dashboard_link(sweep_file, cluster, tmp_path, capsys):
    """the progress line counts every case, and the printed link serves the scheduler's pages"""
    soadyn.sweep(sweep_file, str(tmp_path / "out"), scheduler=cluster.address, batch_size=8)
    err = capsys.readouterr().err
    assert "48/48 cases, 0 failed" in err
    link = re.search(r"^dashboard: (http://\S+)", err, re.M).group(1)
    with urllib.request.urlopen(link, timeout=30) as page:
        body = page.read().decode()
    assert page.status == 200 and "Workers" in body
    # the page lists both workers by address
    for w in cluster.client.scheduler_info()["workers"]:
        assert w.split("://")[1] in body or w in body, w


def killed_sweep(sweep_file, cluster, out):
    """The real command on the real cluster, small tasks (the 4 cases sharing a reference), killed once
    some batches are in.  Returns its parts (name → (mtime, bytes)) once the workers have finished
    the tasks they were running when it died (those still write their parts; the scheduler drops the
    rest with the client), or None when the sweep ended before the kill reached it."""
    p = subprocess.Popen([SOADYN, "sweep", sweep_file, "-o", str(out), "--scheduler", cluster.address, "--batch-size", "1"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    parts = out / "parts"
    deadline = time.monotonic() + 60
    while not (parts.exists() and len(list(parts.glob("*.json"))) >= 3):
        if p.poll() is not None:
            return None
        assert time.monotonic() < deadline, "the sweep stalled before it could be killed"
        time.sleep(0.02)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    seen, still_since = None, time.monotonic()
    while time.monotonic() - still_since < 2.0:  # no new part for 2 s
        now = sorted(f.name for f in parts.glob("*.json"))
        if now != seen:
            seen, still_since = now, time.monotonic()
        time.sleep(0.05)
    return {f.name: (f.stat().st_mtime_ns, f.read_bytes()) for f in parts.glob("*.json")}


def test_killed_sweep_resumes_with_only_the_missing_cases(sweep_file, serial, cluster, tmp_path):
    # a sweep that outran its kill (on two busy cores the polling process can wake after the last
    # batch) resumes nothing: that attempt is set aside and the sweep killed again, up to 5 times
    for attempt in range(5):
        out = tmp_path / f"out{attempt}"
        before = killed_sweep(sweep_file, cluster, out)
        done = 48 if before is None else sum(len(__import__("json").loads(d)) for _, d in before.values())
        if done < 48:
            break
    parts = out / "parts"
    assert 3 <= done < 48
    assert not (out / "results.h5").exists()
    r = soadyn.sweep(sweep_file, str(out), scheduler=cluster.address, quiet=True)
    assert (r.skipped, r.ran) == (done, 48 - done)
    for name, (mtime, data) in before.items():  # finished batches left as they were
        f = parts / name
        assert f.stat().st_mtime_ns == mtime and f.read_bytes() == data
    same_tables(r.table, serial.table)
    # a third run has nothing left to do
    again = soadyn.sweep(sweep_file, str(out), scheduler="serial", quiet=True)
    assert (again.ran, again.skipped) == (0, 48)
    # another sweep refuses this directory
    other = tmp_path / "other.sweep.yaml"
    other.write_text(SWEEP.format(scenarios=SCENARIOS).replace("seed: 7", "seed: 8"))
    with pytest.raises(soadyn.Error, match="holds the results of another sweep"):
        soadyn.sweep(str(other), str(out), scheduler="serial", quiet=True)


def test_a_worker_killed_mid_sweep_loses_no_case(sweep_file, serial, tmp_path):
    c = Cluster(tmp_path, 2)
    try:
        out = tmp_path / "out"
        result = {}
        th = threading.Thread(target=lambda: result.update(
            r=soadyn.sweep(sweep_file, str(out), scheduler=c.address, batch_size=1, quiet=True)))
        th.start()
        deadline = time.monotonic() + 60
        while not ((out / "parts").exists() and len(list((out / "parts").glob("*.json"))) >= 4):
            assert th.is_alive() and time.monotonic() < deadline, "the sweep ended or stalled before a worker could be killed"
            time.sleep(0.01)
        c.workers[0].kill()  # SIGKILL: its running and queued tasks go to the other worker
        at_kill = len(list((out / "parts").glob("*.json")))
        th.join(120)
        assert not th.is_alive()
        assert at_kill < 48, "the sweep finished before the kill"
        assert c.workers[0].wait(10) == -signal.SIGKILL
        r = result["r"]
        assert r.ran == 48
        same_tables(r.table, serial.table)
    finally:
        c.close()


def test_bad_sweep_files(tmp_path):
    def error(text):
        p = tmp_path / "bad.sweep.yaml"
        p.write_text(text.format(s=SCENARIOS))
        return cli_error("sweep", str(p), "-o", str(tmp_path / "out"), "--scheduler", "serial")

    f = str(tmp_path / "bad.sweep.yaml")
    head = "scenario: {s}/double_pendulum.yaml\nvary:\n"
    assert error(head + "  - {{path: bodies.uper.mass, values: [1, 2]}}\n") == \
        f"{f}:3:39: bodies.uper.mass: no entry named 'uper' (the scenario has upper, lower)"
    assert error(head + "  - {{path: bodies.upper.mass, values: [1, -2]}}\n") == \
        f"{f}:3:43: bodies.upper.mass: body 'upper'.mass: expected a positive mass, got '-2'"
    assert error(head + "  - {{path: simulation.method, values: [rk4, rk5]}}\n") == \
        f"{f}:3:45: simulation.method: unknown method 'rk5'; did you mean 'rk4'?"
    assert error(head + "  - path: initial.q[5]\n    values: [1]\n") == f"{f}:4:14: initial.q[5]: index out of range (the model has 2)"
    assert error(head + "  - {{path: simulation.dt, uniform: [2, 1], count: 3}}\n") == \
        f"{f}:3:36: vary[0].uniform: expected [low, high] with low < high, got [2, 1]"
    assert error(head + "  - {{path: simulation.dt, grid: [0.01, 1], count: 2.5}}\n") == \
        f"{f}:3:51: vary[0].count: expected a positive integer, got '2.5'"
    assert error(head + "  - zip:\n    - {{path: simulation.dt, values: [0.1, 0.2]}}\n    - {{path: simulation.rtol, values: [0.1]}}\n") == \
        f"{f}:5:7: vary[0].zip[1]: zip needs equal lengths: 1 cases here, 2 in vary[0].zip[0]"
    assert error("scenario: nothere.yaml\nvary: []\n").startswith(f"{f}:1:11: scenario: cannot read")
    assert "unknown field" in error(head + "  - {{path: simulation.dt, gird: [0.01, 1], count: 2}}\n")
    assert "not valid YAML" in error(head + "  - {{path: simulation.dt, values: [1]\n")


def test_paths_into_lists_and_free_joints():
    sat = os.path.join(SCENARIOS, "satellite_two_arrays.yaml")
    base = soadyn.load_scenario(sat)
    tree = __import__("yaml").safe_load(open(sat).read())
    from soadyn import ensemble
    before = __import__("copy").deepcopy(tree)
    edited = ensemble.apply(tree, base.model, {"initial.q[1]": 0.25, "initial.qd[7]": -0.5, "bodies[0].mass": 123.0})
    assert tree == before  # the edit copies what it changes: the base tree is shared by every case
    scene = soadyn.parse_scenario(__import__("yaml").safe_dump(edited), sat)
    assert scene.q0[1] == 0.25 and scene.v0[7] == -0.5 and scene.model.masses[0] == 123.0
    assert np.array_equal(np.delete(scene.q0, 1), np.delete(base.q0, 1))
    assert np.array_equal(np.delete(scene.v0, 7), np.delete(base.v0, 7))


def test_yaml_12_words_stay_strings(tmp_path):
    """'on' (a dynamics route) and a joint named y are strings, as the scenario parser reads them"""
    p = tmp_path / "routes.sweep.yaml"
    p.write_text(f"scenario: {SCENARIOS}/pendulum_on_cart.yaml\nset: {{simulation.t_end: 0.1, simulation.method: rk4}}\n"
                 "vary:\n  - {path: simulation.dynamics, values: [on, dense, sparse]}\n")
    r = soadyn.sweep(str(p), str(tmp_path / "out"), scheduler="serial", quiet=True, keep_logs=True)
    assert list(r.table["simulation.dynamics"]) == ["on", "dense", "sparse"] and r.failed == 0
    for i in range(3):  # --keep-logs: each case's run log
        log = soadyn.read_log(str(tmp_path / "out" / "logs" / f"case-{i:07d}.h5"))
        assert log.summary.steps == r.table["steps"][i] and log.total_energy[0] == r.table["initial_energy"][i]
    # three routes to the same q̈: the same run to rounding
    assert np.ptp(r.table["max_energy_balance_error"]) < 1e-12


def test_ensemble_charts(serial, tmp_path):
    """tools/ensemble_charts.py: its medians, bands and bounded fractions are the table's"""
    import csv
    tool = os.path.join(os.path.dirname(SCENARIOS), "tools", "ensemble_charts.py")
    p = subprocess.run([sys.executable, tool, serial.path, "-o", str(tmp_path), "--energy-bins", "3"],
                       capture_output=True, text=True, timeout=120, env=dict(os.environ, MPLBACKEND="Agg"))
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "ensemble_wp.png").stat().st_size > 0 and (tmp_path / "ensemble_stability.png").stat().st_size > 0
    t = serial.table
    wp = list(csv.DictReader(open(tmp_path / "ensemble_wp.csv")))
    assert len(wp) == 4
    for r in wp:
        sel = (t["simulation.method"] == r["method"]) & (t["simulation.dt"] == float(r["value"]))
        assert int(r["runs"]) == 12
        p10, p50, p90 = np.percentile(t["state_error"][sel], [10, 50, 90])
        assert float(r["median_error"]) == p50 and float(r["p10_error"]) == p10 and float(r["p90_error"]) == p90
        assert float(r["median_rhs_evals"]) == np.median(t["rhs_evals"][sel])
    st = list(csv.DictReader(open(tmp_path / "ensemble_stability.csv")))
    assert sum(int(r["runs"]) for r in st) == 48
    bounded = t["completed"] & (t["max_energy_balance_error"] <= 0.05)
    for m in ("rk4", "symplectic-euler"):
        rows = [r for r in st if r["method"] == m]
        total = sum(int(r["runs"]) * float(r["fraction_bounded"]) for r in rows)
        assert round(total) == bounded[t["simulation.method"] == m].sum()


def test_index_paths_into_a_ball_joint():
    import yaml
    from soadyn import ensemble
    top = os.path.join(SCENARIOS, "heavy_top.yaml")
    base = soadyn.load_scenario(top)
    tree = yaml.safe_load(open(top).read())
    scene = soadyn.parse_scenario(ensemble._text(ensemble.apply(tree, base.model, {"initial.qd[2]": 7.0})), top)
    assert np.array_equal(scene.v0, [0.0, 0.0, 7.0]) and np.array_equal(scene.q0, base.q0)
    # a quaternion component alone leaves it non-unit: the scenario parser refuses, as for a file
    with pytest.raises(soadyn.Error, match="unit quaternion"):
        soadyn.parse_scenario(ensemble._text(ensemble.apply(tree, base.model, {"initial.q[1]": 0.1})), top)


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2,
                    reason="needs CPU affinity and two CPUs")
def test_embedded_cluster_workers_are_bound_to_their_own_cpus():
    from distributed import Client, LocalCluster
    from soadyn._sweep import _pin_workers
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        before = client.run(os.sched_getaffinity, 0)
        assert all(len(cpus) >= 2 for cpus in before.values())  # the OS's default: any CPU
        _pin_workers(client)
        after = client.run(os.sched_getaffinity, 0)
    bound = sorted(next(iter(cpus)) for cpus in after.values())
    assert all(len(cpus) == 1 for cpus in after.values())
    assert bound == sorted(os.sched_getaffinity(0))[:2]  # one CPU each, not the same one
