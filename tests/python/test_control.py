"""Controllers and joint limits from Python: simulate(..., controller=f) against the closed-form PD
offset, a controller called once per tick when sampled, an exception raised in it (re-raised, the
run file readable up to then), a wrong shape or NaN raised as soadyn.Error naming the time, and
joint-limit events."""
import math

import numpy as np
import pytest

import soadyn

PENDULUM = """gravity: [0, 0, -9.81]
bodies:
  - name: arm
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
"""


def scene(extra=""):
    return soadyn.parse_scenario(PENDULUM + extra, "p.yaml")


def test_python_pd_settles_at_the_gravity_offset():
    kp, kd, thd, mgl = 20.0, 2.0, 0.8, 9.81 * 0.5
    traj = soadyn.simulate(scene("simulation: {t_end: 15, rtol: 1.0e-11, atol: 1.0e-13}\n"),
                           controller=lambda t, q, v: np.array([kp * (thd - q[0]) - kd * v[0]]))
    assert traj.summary.completed, traj.summary.status
    th = thd
    for _ in range(50):  # m g l sin θ = K_p (θ_d − θ)
        th -= (mgl * math.sin(th) - kp * (thd - th)) / (mgl * math.cos(th) + kp)
    assert abs(traj.q[-1, 0] - th) < 1e-8
    assert abs(traj.control[-1, 0] - kp * (thd - th)) < 1e-6
    assert traj.summary.max_energy_balance_error < 1e-7


def test_sampled_controller_is_called_once_per_tick():
    times = []

    def f(t, q, v):
        times.append(t)
        return [-10.0 * q[0] - v[0]]  # any sequence of nv numbers

    traj = soadyn.simulate(scene("initial: {q: {arm: 0.5}}\nsimulation: {t_end: 0.2, control_dt: 0.01, output_dt: 0.001}\n"),
                           controller=f)
    assert traj.summary.completed and traj.summary.control_ticks == 21
    assert np.allclose(times, 0.01 * np.arange(21), atol=1e-12)
    between = np.abs(traj.t / 0.01 - np.round(traj.t / 0.01)) > 1e-6
    jumps = np.abs(np.diff(traj.control[:, 0])) > 1e-14
    assert not np.any(jumps & between[1:])  # τ changes only at ticks


def test_controller_exception_is_reraised_and_the_file_stays_readable(tmp_path):
    out = tmp_path / "run.h5"

    def f(t, q, v):
        if t > 0.3:
            raise ValueError("encoder fault")
        return np.zeros(1)

    with pytest.raises(ValueError, match="encoder fault") as info:
        soadyn.simulate(scene("initial: {q: {arm: 0.5}}\nsimulation: {t_end: 1}\n"), controller=f, output=str(out))
    partial = info.value.trajectory
    assert 0.25 < partial.t[-1] <= 0.3 + 1e-9  # the rows before the step that crossed t = 0.3
    back = soadyn.read_log(str(out))
    assert not back.summary.completed
    assert "the controller raised at t = 0.3" in back.summary.status and "encoder fault" in back.summary.status
    assert np.array_equal(back.t, partial.t)


def test_wrong_shape_and_nan_are_one_error_naming_the_time():
    # raised as soadyn.Error with the partial Trajectory (test_no_silent_results.py: the file's rows)
    with pytest.raises(soadyn.Error) as info:
        soadyn.simulate(scene("simulation: {t_end: 1, control_dt: 0.1}\n"), controller=lambda t, q, v: np.zeros(2))
    assert "the controller returned shape (2,) at t = 0 s; expected 1 torques, shape (1,)" == str(info.value)
    assert not info.value.trajectory.summary.completed
    with pytest.raises(soadyn.Error) as info:
        soadyn.simulate(scene("simulation: {t_end: 1, control_dt: 0.1}\n"),
                        controller=lambda t, q, v: [math.nan if t > 0.15 else 0.0])
    assert "non-finite torque at t = 0.2 s (arm = nan)" in str(info.value)
    assert "non-finite torque at t = 0.2 s (arm = nan)" in info.value.trajectory.summary.status


def test_limit_events_in_the_summary():
    traj = soadyn.simulate(scene("initial: {q: {arm: 1.0}}\nlimits: {arm: [0.0, 3.0]}\n"
                                 "simulation: {t_end: 1.0, rtol: 1.0e-12, atol: 1.0e-14, limits: true, restitution: 0.5}\n"))
    ev = traj.summary.events
    assert ev and ev[0]["kind"] == "impact" and ev[0]["joint"] == "arm" and ev[0]["side"] == "lower"
    w0 = math.sqrt(9.81 * 0.5 / (0.08 + 0.25))
    assert abs(ev[0]["v_before"] + 2 * w0 * math.sin(0.5)) < 1e-8
    assert abs(ev[0]["v_after"] + 0.5 * ev[0]["v_before"]) < 1e-12
    assert traj.q[:, 0].min() > -1e-9
    assert abs(traj.impact_loss[-1] - sum(e["energy_lost"] for e in ev)) < 1e-12
    assert np.max(np.abs(traj.balance_error)) < 1e-8
