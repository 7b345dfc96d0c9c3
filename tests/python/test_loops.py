"""Closed loops from Python: scenarios/four_bar.yaml (a crank-rocker assembled from its crank's
angle) simulated, its loop's multipliers named and shaped as the run file's /loops/force, the loop
held closed and the energy kept, the run file read back whole, and the assembly's geometry: the
coupler's end on the rocker's end at the start."""
import math
import os

import numpy as np
import pytest

import soadyn

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE = os.path.join(ROOT, "scenarios", "four_bar.yaml")


def test_the_four_bar_stays_closed_and_logs_its_loop_forces(tmp_path):
    sc = soadyn.load_scenario(SCENE)
    out = str(tmp_path / "four_bar.h5")
    traj = soadyn.simulate(sc, t_end=4.0, output=out)
    assert traj.summary.completed, traj.summary.status
    assert traj.loop_rows == ["closing.x", "closing.y", "closing.z", "closing.n1", "closing.n2"]
    assert traj.loop_forces.shape == (len(traj.t), 5)
    assert traj.loop_closure.max() < 1e-10
    assert abs(traj.balance_error).max() < 1e-8
    # in the plane: the hinge carries forces along x and y, none along z and no moments about x, y
    assert abs(traj.loop_forces[:, :2]).max() > 1.0
    assert abs(traj.loop_forces[:, 2:]).max() < 1e-6
    back = soadyn.read_log(out)
    assert back.loop_rows == traj.loop_rows
    np.testing.assert_array_equal(back.loop_forces, traj.loop_forces)
    np.testing.assert_array_equal(back.loop_closure, traj.loop_closure)


def test_the_initial_state_is_assembled_from_the_cranks_angle():
    sc = soadyn.load_scenario(SCENE)
    traj = soadyn.simulate(sc, t_end=0.01)
    crank, coupler, rocker = traj.q[0]
    assert crank == pytest.approx(0.7, abs=1e-15)  # held, as initial.q names it
    # the coupler's end (1.0 m from the crank's end, 0.3 m from O) on the rocker's end (0.8 m from (0.9, 0))
    b = np.array([0.3 * math.cos(crank), 0.3 * math.sin(crank)])
    c1 = b + 1.0 * np.array([math.cos(crank + coupler), math.sin(crank + coupler)])
    c2 = np.array([0.9, 0.0]) + 0.8 * np.array([math.cos(rocker), math.sin(rocker)])
    np.testing.assert_allclose(c1, c2, atol=1e-12)
    assert traj.v[0, 0] == pytest.approx(3.0, abs=1e-15)


def test_a_run_without_loops_has_none():
    sc = soadyn.load_scenario(os.path.join(ROOT, "scenarios", "double_pendulum.yaml"))
    traj = soadyn.simulate(sc, t_end=0.1)
    assert traj.loop_rows == [] and traj.loop_forces.shape == (len(traj.t), 0)


def test_a_pickled_scene_keeps_its_loops_and_its_prescribed_motion():
    """a scene sent to a Dask worker (pickled) runs the same: its loops and prescribed motion with it"""
    import pickle
    sc = soadyn.load_scenario(SCENE)
    back = pickle.loads(pickle.dumps(sc))
    a, b = soadyn.simulate(sc, t_end=0.5), soadyn.simulate(back, t_end=0.5)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.loop_forces, b.loop_forces)
    crane = soadyn.load_scenario(os.path.join(ROOT, "scenarios", "crane_slew.yaml"))
    a, b = soadyn.simulate(crane, t_end=2.0), soadyn.simulate(pickle.loads(pickle.dumps(crane)), t_end=2.0)
    assert b.prescribed_joints == ["trolley"]
    np.testing.assert_array_equal(a.prescribed_torque, b.prescribed_torque)
