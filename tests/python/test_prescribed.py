"""Prescribed motion from Python: simulate(scene, prescribed={"joint": f}) with f(t) -> (q, qd, qdd)
against a pendulum on a cart whose cart is driven (the pendulum's closed form for a cart held at
constant acceleration a: the pendulum settles about atan(a/g)), the logged torques against inverse
dynamics, the energy books, the scene's own prescribed: and its run file read back whole
(prescribed_torque, prescribed_joints, work_prescribed), and a motion that raises."""
import math
import os

import numpy as np
import pytest

import soadyn

CART = """gravity: [0, 0, -9.81]
bodies:
  - name: cart
    joint: {type: prismatic, name: slide, axis: [1, 0, 0]}
    mass: 2.0
    inertia: [0.1, 0.1, 0.1]
  - name: pole
    parent: cart
    joint: {type: revolute, name: hinge, axis: [0, 1, 0]}
    mass: 0.5
    com: [0, 0, -0.8]
    inertia: [0.01, 0.01, 0.001]
simulation: {t_end: 3.0, output_dt: 0.01, rtol: 1.0e-11, atol: 1.0e-12}
"""


def test_a_driven_cart_gives_the_torques_inverse_dynamics_asks_for():
    sc = soadyn.parse_scenario(CART, "cart.yaml")
    a = 1.5
    traj = soadyn.simulate(sc, prescribed={"slide": lambda t: (0.5 * a * t * t, a * t, a)})
    assert traj.summary.completed, traj.summary.status
    assert traj.prescribed_joints == ["slide"]
    assert traj.prescribed_torque.shape == (len(traj.t), 1)
    np.testing.assert_allclose(traj.q[:, 0], 0.5 * a * traj.t ** 2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.qdd[:, 0], a, rtol=0, atol=1e-12)
    # the force on the cart is inverse dynamics' on the whole model at the logged motion
    model, data = sc.model, soadyn.Data(sc.model)
    for k in range(0, len(traj.t), 37):
        tau = soadyn.inverse_dynamics(model, data, traj.q[k], traj.v[k], traj.qdd[k])
        assert tau[1] == pytest.approx(0.0, abs=1e-9)
        assert tau[0] == pytest.approx(traj.prescribed_torque[k, 0], rel=1e-9)
    # held at constant acceleration from rest, the pole swings about atan(a/g) (trailing the cart:
    # its centre of mass behind, a positive turn about +y), between 0 and twice that, undamped
    lean = math.atan(a / 9.81)
    assert traj.q[:, 1].max() == pytest.approx(2 * lean, rel=2e-3)
    # E − E(0) = W_p (no other input does work)
    assert abs(traj.balance_error).max() < 1e-8
    assert traj.work_prescribed[-1] > 1.0


def test_the_scenes_prescribed_motion_and_its_run_file(tmp_path):
    sc = soadyn.parse_scenario(CART + "prescribed: {slide: {slew: {from: 0, to: 2, start: 0.5, duration: 2}}}\n",
                               str(tmp_path / "cart.yaml"))
    out = str(tmp_path / "cart.h5")
    traj = soadyn.simulate(sc, output=out)
    back = soadyn.read_log(out)
    assert back.prescribed_joints == ["slide"]
    np.testing.assert_array_equal(back.prescribed_torque, traj.prescribed_torque)
    np.testing.assert_array_equal(back.work_prescribed, traj.work_prescribed)
    assert traj.q[-1, 0] == pytest.approx(2.0, abs=1e-15)
    # at rest before and after the slew: the cart's force is the pole's pull alone
    assert abs(traj.v[traj.t < 0.5, 0]).max() < 1e-15
    assert abs(traj.balance_error).max() < 1e-8
    # the Python motion overrides the scene's
    over = soadyn.simulate(sc, prescribed={"slide": lambda t: (0.0, 0.0, 0.0)})
    assert abs(over.q[:, 0]).max() == 0.0


def test_a_motion_that_raises_ends_the_run_and_is_re_raised():
    sc = soadyn.parse_scenario(CART, "cart.yaml")

    def motion(t):
        if t > 1.0:
            raise ValueError("no data past 1 s")
        return (0.0, 0.0, 0.0)

    with pytest.raises(ValueError, match="no data past 1 s"):
        soadyn.simulate(sc, prescribed={"slide": motion})
    with pytest.raises(soadyn.Error, match="expected \\(q, qd, qdd\\)"):
        soadyn.simulate(sc, prescribed={"slide": lambda t: (0.0, 0.0)})
    with pytest.raises(soadyn.Error, match="no joint named 'slider'"):
        soadyn.simulate(sc, prescribed={"slider": lambda t: (0.0, 0.0, 0.0)})


SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenarios")


def test_the_three_scenes():
    # the gimbal's slew on a free-floating satellite: the bus turns in reaction, the angular
    # momentum (zero at the start) stays within 1e-9 kg m²/s
    ant = soadyn.simulate(os.path.join(SCENES, "antenna_slew.yaml"))
    assert ant.summary.completed
    assert ant.prescribed_joints == ["azimuth", "elevation"]
    assert np.linalg.norm(ant.angular_momentum, axis=1).max() <= 1e-9
    assert np.linalg.norm(ant.linear_momentum, axis=1).max() <= 1e-9
    assert ant.q[-1, 7] == pytest.approx(math.pi / 2, abs=1e-15)
    assert 2 * math.acos(min(1.0, abs(ant.q[-1, 3]))) > 0.05  # the bus's attitude reaction, rad
    assert abs(ant.prescribed_torque[ant.t < 5.0]).max() < 1e-12  # nothing to hold before the slew
    # the crane: the trolley ends its move at rest 4 m on, the load still swings
    crane = soadyn.simulate(os.path.join(SCENES, "crane_slew.yaml"))
    assert crane.q[-1, 0] == pytest.approx(4.0, abs=1e-15)
    after = crane.t > 7.0
    assert abs(crane.v[after, 0]).max() == 0.0
    assert abs(crane.q[after, 1]).max() > 0.01
    assert abs(crane.balance_error).max() < 1e-8
    # the arm: the shoulder passes through the table's samples
    arm = soadyn.simulate(os.path.join(SCENES, "arm_replay.yaml"))
    table = np.loadtxt(os.path.join(SCENES, "shoulder_replay.csv"), delimiter=",", skiprows=1)
    at = np.searchsorted(arm.t, table[:, 0] - 1e-12)
    np.testing.assert_allclose(arm.q[at, 0], table[:, 1], rtol=0, atol=1e-12)
    assert abs(arm.balance_error).max() < 1e-8


def test_sensitivities_of_the_free_joints_with_a_driven_cart():
    """the run's sensitivities are the pole's alone (the cart's motion is given), and its ∂x/∂x₀
    agrees with a difference of two runs"""
    sc = soadyn.parse_scenario(CART, "cart.yaml")
    a = 1.5
    drive = {"slide": lambda t: (0.5 * a * t * t, a * t, a)}
    traj = soadyn.simulate(sc, prescribed=drive, sensitivities={"initial_state": True, "parameters": ["pole"]})
    sens = traj.sensitivities
    assert sens.state_names == ["q.hinge", "qd.hinge"], sens.state_names
    assert sens.initial_state.shape == (len(traj.t), 2, 2)
    assert sens.parameters.shape == (len(traj.t), 2, 10)
    # ∂θ(T)/∂θ₀ by a central difference of whole runs from θ₀ ± h
    h = 1e-5
    ends = []
    for sign in (1, -1):
        moved = soadyn.parse_scenario(CART.replace("simulation:", f"initial: {{q: {{hinge: {sign * h}}}}}\nsimulation:"),
                                      "cart.yaml")
        ends.append(soadyn.simulate(moved, prescribed=drive).q[-1, 1])
    assert sens.initial_state[-1, 0, 0] == pytest.approx((ends[0] - ends[1]) / (2 * h), rel=1e-5)
