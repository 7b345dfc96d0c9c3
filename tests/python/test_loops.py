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


DELTA = os.path.join(ROOT, "scenarios", "delta_robot.yaml")


def test_the_delta_robots_motor_torques_by_constrained_inverse_dynamics():
    """The Delta robot's three loops from Python: at states of a run, the motors' torques that
    make the logged motion (loop_inverse_dynamics, the motors actuated) are those the run's
    computed-torque controller applied; forward dynamics with the loops under them gives the motion
    back, every joint's q̈, and the same loop forces"""
    sc = soadyn.load_scenario(DELTA)
    assert sc.loop_rows == [f"wrist{i}.{c}" for i in range(3) for c in "xyz"]
    assert sc.loop_units == ["N"] * 9
    with pytest.warns(RuntimeWarning, match="assembled onto the loops"):
        traj = soadyn.simulate(sc, t_end=0.5)
    assert traj.summary.completed, traj.summary.status
    motors = ["motor0", "motor1", "motor2"]
    dofs = [sc.model.joint_names.index(m) for m in motors]  # one DOF per body, in body order
    for k in range(0, len(traj.t), 20):
        q, v, qdd = traj.q[k], traj.v[k], traj.qdd[k]
        wanted = np.zeros(sc.model.nv)
        wanted[dofs] = qdd[dofs]
        tau, lam, full = soadyn.loop_inverse_dynamics(sc, q, v, wanted, actuated=motors)
        np.testing.assert_allclose(full, qdd, rtol=0, atol=1e-7 * max(1.0, abs(qdd).max()))
        np.testing.assert_allclose(tau, traj.control[k], rtol=0, atol=1e-7 * max(1.0, abs(tau).max()))
        assert abs(tau[dofs]).max() > 0.1 and np.count_nonzero(tau) == 3
        back, lam2 = soadyn.loop_forward_dynamics(sc, q, v, tau)
        np.testing.assert_allclose(back, qdd, rtol=0, atol=1e-7 * max(1.0, abs(qdd).max()))
        np.testing.assert_allclose(lam2, lam, rtol=0, atol=1e-7 * max(1.0, abs(lam).max()))


def test_constrained_inverse_dynamics_refuses_too_few_actuators_and_a_scene_without_loops():
    sc = soadyn.load_scenario(DELTA)
    traj = soadyn.simulate(sc, t_end=0.01)
    with pytest.raises(soadyn.Error, match="passive DOF"):
        soadyn.loop_inverse_dynamics(sc, traj.q[0], traj.v[0], np.zeros(sc.model.nv), actuated=["motor0"])
    with pytest.raises(KeyError, match="motr0"):
        soadyn.loop_inverse_dynamics(sc, traj.q[0], traj.v[0], np.zeros(sc.model.nv), actuated=["motr0"])
    cart = soadyn.load_scenario(os.path.join(ROOT, "scenarios", "pendulum_on_cart.yaml"))
    with pytest.raises(soadyn.Error, match="has no closed loops"):
        soadyn.loop_forward_dynamics(cart, cart.q0, cart.v0)
