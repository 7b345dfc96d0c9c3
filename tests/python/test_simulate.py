"""simulate() and read_log(): the same trajectory both ways, the summary, the GIL released while
integrating, and Ctrl-C (a real SIGINT to a real process) ending a run cleanly with a readable file."""
import os
import select
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import soadyn
from conftest import ROOT, SCENARIOS, assert_close, cli


@pytest.mark.parametrize("scene,method", [("satellite_two_arrays", "cvode-adams"), ("double_pendulum", "rk4"),
                                          ("stiff_arm", "cvode-bdf")])
def test_simulate_and_read_log_give_identical_trajectories(tmp_path, scene, method):
    out = tmp_path / "run.h5"
    traj = soadyn.simulate(f"{SCENARIOS}/{scene}.yaml", method, t_end=1.0, output=str(out))
    back = soadyn.read_log(str(out))
    assert traj.summary.completed and traj.summary.status == "completed"
    for name in traj.ARRAYS:
        a, b = getattr(traj, name), getattr(back, name)
        assert a.dtype == np.float64 and a.shape == b.shape and a.shape[0] == len(traj), name
        assert np.array_equal(a, b), name
    assert traj.summary == back.summary
    assert (traj.joint_names, traj.parents, traj.scenario) == (back.joint_names, back.parents, back.scenario)
    model = soadyn.load(f"{SCENARIOS}/{scene}.yaml")
    assert traj.q.shape == (len(traj), model.nq) and traj.v.shape == (len(traj), model.nv)
    assert traj.linear_momentum.shape == (len(traj), 3)
    assert traj.t[0] == 0.0 and traj.t[-1] == 1.0 == traj.summary.t_reached


def test_simulate_equals_the_command_line_run(tmp_path):
    """the module's run and `soadyn run` log the same numbers"""
    path = f"{SCENARIOS}/three_link_arm.yaml"
    traj = soadyn.simulate(path, "rk4", dt=1e-3, t_end=0.5)
    p = cli("run", path, "--method", "rk4", "--dt", "1e-3", "--t-end", "0.5", "-q", "-o", tmp_path / "cli.h5")
    assert p.returncode == 0, p.stderr
    ref = soadyn.read_log(str(tmp_path / "cli.h5"))
    for name in traj.ARRAYS:
        assert np.array_equal(getattr(traj, name), getattr(ref, name)), name
    assert traj.summary.steps == ref.summary.steps == 500


def test_trajectory_is_physical():
    """the satellite conserves energy and momentum; the trajectory's own arrays say so"""
    traj = soadyn.simulate(f"{SCENARIOS}/satellite_two_arrays.yaml", t_end=5.0, rtol=1e-10)
    assert np.abs(traj.energy_error).max() == pytest.approx(traj.summary.max_energy_balance_error, rel=1e-12)
    assert np.abs(traj.energy_error).max() < 1e-7
    assert_close(traj.linear_momentum, np.broadcast_to(traj.linear_momentum[0], traj.linear_momentum.shape), 1e-8)
    assert_close(traj.angular_momentum, np.broadcast_to(traj.angular_momentum[0], traj.angular_momentum.shape), 1e-8)
    assert_close(np.linalg.norm(traj.q[:, 3:7], axis=1), np.ones(len(traj)), 1e-9)


def test_energy_balance_and_body_poses(tmp_path):
    """a driven, damped scene: E − E0 = W to the tolerance, D ≥ 0 and growing; body poses as T×N×3/4"""
    out = tmp_path / "driven.h5"
    traj = soadyn.simulate(f"{SCENARIOS}/driven_pendulum.yaml", t_end=3.0, rtol=1e-9, output=str(out))
    E = traj.total_energy
    assert np.abs(E - E[0]).max() > 0.1, "the inputs change the energy"
    assert np.abs(traj.balance_error).max() == pytest.approx(traj.summary.max_energy_balance_error, rel=1e-12)
    assert traj.summary.max_energy_balance_error < 1e-7
    assert traj.dissipated[-1] > 0 and np.all(np.diff(traj.dissipated) >= 0)
    assert traj.body_position.shape == (len(traj), 2, 3) and traj.body_orientation.shape == (len(traj), 2, 4)
    assert_close(np.linalg.norm(traj.body_orientation, axis=2), np.ones((len(traj), 2)), 1e-12)
    # the lower link's frame origin is the elbow: 1 m down the upper link, which turns about x
    th = traj.q[:, 0]
    assert_close(traj.body_position[:, 1], np.stack([0 * th, np.sin(th), -np.cos(th)], axis=1), 1e-12)


def test_a_lean_log_reads_back_with_nan_for_what_it_left_out(tmp_path):
    out = tmp_path / "lean.h5"
    p = cli("run", f"{SCENARIOS}/three_link_arm.yaml", "--log", "energy", "--t-end", "0.2", "-q", "-o", out)
    assert p.returncode == 0, p.stderr
    back = soadyn.read_log(str(out))
    full = soadyn.simulate(f"{SCENARIOS}/three_link_arm.yaml", t_end=0.2)
    assert np.array_equal(back.total_energy, full.total_energy) and np.array_equal(back.t, full.t)
    assert np.isnan(back.q).all() and back.q.shape == full.q.shape
    assert np.isnan(back.body_com).all() and back.body_com.shape == full.body_com.shape
    assert back.summary.max_energy_balance_error == full.summary.max_energy_balance_error


def test_a_failed_run_returns_what_it_has(tmp_path):
    """explicit Euler far past its stability limit: no exception, the summary says why"""
    traj = soadyn.simulate(f"{SCENARIOS}/stiff_arm.yaml", "euler", dt=0.05, t_end=20.0, output=str(tmp_path / "x.h5"))
    assert not traj.summary.completed and "unstable" in traj.summary.status
    assert traj.t[-1] <= traj.summary.t_reached < 20.0  # t_reached: where it failed
    back = soadyn.read_log(str(tmp_path / "x.h5"))
    assert back.summary.status == traj.summary.status and np.array_equal(back.q, traj.q)


def test_the_gil_is_released_while_integrating():
    """another Python thread keeps running while simulate() integrates"""
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    ticks, done = [], threading.Event()

    def run():
        soadyn.simulate(scene, "rk4", dt=2e-5, t_end=20.0, output_dt=10.0)
        done.set()

    worker = threading.Thread(target=run)
    start = time.monotonic()
    worker.start()
    while not done.is_set():
        ticks.append(time.monotonic())
        sum(range(2000))  # pure-Python work that needs the GIL
    worker.join()
    took = time.monotonic() - start
    gaps = np.diff([start] + ticks)
    assert took > 0.2, "the run should take a while"
    # holding the GIL, simulate() would freeze this loop for the whole run
    assert gaps.max() < 0.5 * took, (gaps.max(), took)


CHILD = textwrap.dedent("""
    import sys, time, soadyn
    scene = soadyn.load_scenario(sys.argv[1])
    print("running", flush=True)
    try:
        soadyn.simulate(scene, "rk4", dt=1e-4, t_end=1e6, output=sys.argv[2])
    except KeyboardInterrupt as e:
        t = e.trajectory
        print("interrupted", len(t), repr(t.t[-1]), t.summary.status, flush=True)
        sys.exit(0)
    print("completed", flush=True)
    sys.exit(1)
""")


def test_ctrl_c_stops_a_long_run_within_a_tenth_of_a_second(tmp_path):
    out = tmp_path / "long.h5"
    child = subprocess.Popen([sys.executable, "-c", CHILD, f"{SCENARIOS}/double_pendulum.yaml", str(out)],
                             stdout=subprocess.PIPE, text=True, env=dict(os.environ))
    try:
        assert child.stdout.readline().strip() == "running"
        time.sleep(1.0)  # well inside the run (1e6 s of simulated time would take hours)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        ready, _, _ = select.select([child.stdout], [], [], 10.0)
        assert ready, "still running 10 s after SIGINT"
        line = child.stdout.readline().split()
        latency = time.monotonic() - sent
        assert child.wait(timeout=30) == 0
    finally:
        child.kill()
    print(f"Ctrl-C to KeyboardInterrupt handled: {latency * 1e3:.1f} ms")
    assert line[0] == "interrupted", line
    samples, t_last, status = int(line[1]), float(line[2]), " ".join(line[3:])
    assert latency < 0.1, latency
    assert status == f"interrupted by SIGINT at t = {t_last:.9g}", status  # the library prints t with %.9g
    assert 0.0 < t_last < 1e6
    # the file is complete and readable, and holds exactly what the run returned
    back = soadyn.read_log(str(out))
    assert back.summary.status == status and not back.summary.completed
    assert len(back) == samples and back.t[-1] == t_last == back.summary.t_reached
    assert np.all(np.isfinite(back.q)) and np.all(np.diff(back.t) > 0)


def test_a_stiff_adams_run_says_so_once(tmp_path):
    """stiff_arm under cvode-adams: one RuntimeWarning naming cvode-bdf, the summary's hint and
    index, the same in the run file (read_log) and one 'soadyn: hint:' line from the command
    line; under cvode-bdf none of it"""
    scene = f"{SCENARIOS}/stiff_arm.yaml"
    out = tmp_path / "stiff.h5"
    with pytest.warns(RuntimeWarning, match="cvode-bdf") as said:
        tr = soadyn.simulate(scene, method="cvode-adams", t_end=0.3, output=str(out))
    assert sum("looks stiff" in str(w.message) for w in said) == 1
    assert tr.summary.stiffness_index >= 0.2 and "cvode-bdf" in tr.summary.stiffness_hint
    back = soadyn.read_log(str(out)).summary
    assert back.stiffness_hint == tr.summary.stiffness_hint
    assert back.stiffness_index == pytest.approx(tr.summary.stiffness_index, rel=1e-12)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        calm = soadyn.simulate(scene, method="cvode-bdf", t_end=0.3)
    assert calm.summary.stiffness_hint == "" and calm.summary.stiffness_index == 0.0
    p = cli("run", scene, "--method", "cvode-adams", "--t-end", "0.3", "-q", "-o", tmp_path / "cli.h5")
    assert p.returncode == 0, p.stderr
    hints = [line for line in p.stderr.splitlines() if line.startswith("soadyn: hint: the run looks stiff")]
    assert len(hints) == 1 and "cvode-bdf" in hints[0], p.stderr
