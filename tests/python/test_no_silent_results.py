"""Results that would be wrong without a word are refused or raised instead:
rollout on a scene whose controllers or joint limits it does not apply (refused, while simulate on
the same scene holds the limit); free and ball joints' quaternions far from unit norm (zero, NaN,
2×) given as initial states from Python (Scenario.q0, rollout, simulate) or a scenario file, with
near-unit ones normalized; a Python controller returning NaN or the wrong shape (soadyn.Error naming
the time, the partial Trajectory on it, and the output file keeping its rows)."""
import math

import h5py
import numpy as np
import pytest

from conftest import SCENARIOS

import soadyn

ARM = f"{SCENARIOS}/arm_control_limits.yaml"


# ---- rollout: controllers and limits ----------------------------------------------------------

def test_rollout_refuses_what_it_does_not_apply_where_simulate_holds_the_limit():
    scene = soadyn.load_scenario(ARM)
    traj = soadyn.simulate(scene, t_end=0.5)  # the elbow hits 2.5 rad at 0.07 s and rebounds
    elbow = scene.model.q_names.index("elbow")
    assert traj.summary.completed and traj.summary.events
    assert traj.q[:, elbow].max() <= 2.5 + 1e-9
    y0 = np.r_[scene.q0, scene.v0][None, :]
    for given in (scene, ARM):  # a Scenario and a path alike
        for method in (None, "rk4", "cvode-bdf"):
            with pytest.raises(soadyn.Error) as info:
                soadyn.rollout(given, y0, steps=50, dt=0.01, method=method)
            msg = str(info.value)
            assert msg.startswith(f"rollout: {ARM}: rollout does not apply the scene's built-in controllers "
                                  "(gravity_compensation, pd on shoulder, pd on elbow) and its joint limits "
                                  "(simulation: limits: true)"), msg
            assert "soadyn.simulate" in msg and "\n" not in msg


@pytest.mark.parametrize("extra, what", [
    ("inputs: {controllers: [{type: pd, joint: arm, kp: 4, kd: 1, target: 0.2}]}\n", "built-in controllers (pd on arm)"),
    ("limits: {arm: [-1, 1]}\nsimulation: {limits: true}\n", "joint limits (simulation: limits: true)"),
])
def test_rollout_refuses_controllers_or_limits_alone(extra, what):
    scene = soadyn.parse_scenario(PENDULUM + extra, "p.yaml")
    with pytest.raises(soadyn.Error, match=r"rollout: p\.yaml: rollout does not apply the scene's " + what.replace("(", r"\(").replace(")", r"\)")):
        soadyn.rollout(scene, np.array([[0.1, 0.0]]), steps=3)
    # limits declared but not enforced (limits: false, the default): the run is the scene's, rolled out
    if "limits" in extra:
        plain = soadyn.parse_scenario(PENDULUM + "limits: {arm: [-1, 1]}\n", "p.yaml")
        states, _ = soadyn.rollout(plain, np.array([[0.1, 0.0]]), steps=3)
        assert np.isfinite(states).all()


def test_rollout_callback_returning_nan_is_named():
    scene = soadyn.parse_scenario(PENDULUM, "p.yaml")
    with pytest.raises(soadyn.Error, match=r"rollout: controls: the callback returned nan at entry 0 for rollout 1, step 2"):
        soadyn.rollout(scene, np.zeros((2, 2)), lambda k, s, t, y: [math.nan if (k, s) == (1, 2) else 0.0], steps=4)


# ---- quaternions ------------------------------------------------------------------------------

PENDULUM = """gravity: [0, 0, -9.81]
bodies:
  - name: arm
    joint: {type: revolute, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.08, 0.08, 0.01]
"""

FLOATING = """gravity: [0, 0, -9.81]
bodies:
  - name: base
    joint: {type: free}
    mass: 2.0
    inertia: [0.1, 0.2, 0.3]
  - name: ball
    parent: base
    joint: {type: ball}
    origin: {xyz: [0, 0, -0.3]}
    mass: 1.0
    com: [0, 0, -0.2]
    inertia: [0.01, 0.01, 0.01]
simulation: {t_end: 0.05}
"""

BAD = [([0, 0, 0, 0], "got norm 0"), ([math.nan, 0, 0, 0], "got norm nan"), ([2, 0, 0, 0], "got norm 2"),
       ([0.999, 0, 0, 0], "got norm 0.999")]


@pytest.mark.parametrize("joint", ["base", "ball"])
@pytest.mark.parametrize("quat, said", BAD)
def test_far_from_unit_quaternions_refused_from_python(joint, quat, said):
    scene = soadyn.parse_scenario(FLOATING, "f.yaml")
    q = scene.q0.copy()
    at = 3 if joint == "base" else 7  # free: [x y z, w x y z]; ball: [w x y z]
    q[at:at + 4] = quat
    # NaN: refused as not finite before its norm is looked at
    nan = r"|.*\[[\d, ]+\] = nan: expected a finite number|.*is nan: expected a finite number"
    with pytest.raises(soadyn.Error, match=rf"Scenario.q0: (joint '{joint}': expected a unit quaternion .*{said}$" +
                       (nan if "nan" in said else "") + ")"):
        scene.q0 = q
    assert np.allclose(scene.q0[at:at + 4], [1, 0, 0, 0])  # unchanged
    y0 = np.r_[scene.q0, scene.v0][None, :].repeat(2, axis=0)
    y0[1, at:at + 4] = quat
    with pytest.raises(soadyn.Error, match=rf"rollout: initial_states(\[1\]: joint '{joint}': .*{said}$" +
                       (nan if "nan" in said else "") + ")"):
        soadyn.rollout(scene.model, y0, steps=2)


def test_near_unit_quaternion_is_normalized():
    scene = soadyn.parse_scenario(FLOATING, "f.yaml")
    q = scene.q0.copy()
    q[3:7] = [1 + 5e-7, 0, 0, 0]
    q[7:11] = [0.6, 0.8 * (1 - 5e-7), 0, 0]
    scene.q0 = q
    assert abs(np.linalg.norm(scene.q0[3:7]) - 1) < 1e-15 and abs(np.linalg.norm(scene.q0[7:11]) - 1) < 1e-15
    traj = soadyn.simulate(scene)
    assert traj.summary.completed and np.isfinite(traj.q).all()
    assert np.abs(np.linalg.norm(traj.q[:, 3:7], axis=1) - 1).max() < 1e-9


@pytest.mark.parametrize("quat, said", [("[0, 0, 0, 0]", "got norm 0"), ("[2, 0, 0, 0]", "got norm 2")])
def test_far_from_unit_quaternion_refused_in_a_scenario_file(tmp_path, quat, said):
    path = tmp_path / "f.yaml"
    path.write_text(FLOATING + f"initial:\n  q: {{ball: {quat}}}\n")
    with pytest.raises(soadyn.Error) as info:
        soadyn.load_scenario(str(path))
    msg = str(info.value)
    assert msg.startswith(f"{path}:16:") and "initial.q.ball" in msg and said in msg and "\n" not in msg, msg


# ---- a Python controller's bad torque ---------------------------------------------------------

@pytest.mark.parametrize("control_dt", [0.1, 0.0])
@pytest.mark.parametrize("bad, said", [
    (lambda t: [math.nan], r"the controller returned a non-finite torque at t = 0\.\d+ s \(arm = nan\)"),
    (lambda t: np.zeros(2), r"the controller returned shape \(2,\) at t = 0\.\d+ s; expected 1 torques, shape \(1,\)"),
    (lambda t: [[0.0]], r"the controller returned shape \(1, 1\) at t = 0\.\d+ s"),
    (lambda t: None, r"the controller returned shape \(\) at t = 0\.\d+ s"),  # None: a 0-d array
])
def test_bad_controller_torque_raises_and_the_file_keeps_its_rows(tmp_path, control_dt, bad, said):
    out = tmp_path / "run.h5"
    scene = soadyn.parse_scenario(PENDULUM + f"initial: {{q: {{arm: 0.5}}}}\nsimulation: {{t_end: 1, control_dt: {control_dt}}}\n",
                                  "p.yaml")

    def controller(t, q, v):
        return bad(t) if t > 0.25 else np.array([-2.0 * q[0]])

    with pytest.raises(soadyn.Error, match=said) as info:
        soadyn.simulate(scene, controller=controller, output=str(out))
    partial = info.value.trajectory
    assert len(partial.t) > 5 and 0.2 < partial.t[-1] <= 0.3 + 1e-9  # rows up to the bad torque
    assert np.isfinite(partial.q).all()
    back = soadyn.read_log(str(out))
    assert not back.summary.completed and "the controller returned" in back.summary.status
    assert np.array_equal(back.t, partial.t) and np.array_equal(back.q, partial.q)
    with h5py.File(out, "r") as f:
        assert f["q"].shape[0] == len(partial.t)


def test_bad_torque_at_the_first_sample_raises_with_no_rows():
    scene = soadyn.parse_scenario(PENDULUM + "simulation: {t_end: 1, control_dt: 0.1}\n", "p.yaml")
    with pytest.raises(soadyn.Error, match=r"non-finite torque at t = 0 s \(arm = inf\)") as info:
        soadyn.simulate(scene, controller=lambda t, q, v: [math.inf])
    assert len(info.value.trajectory.t) == 0
