"""Forward sensitivities from Python: soadyn.simulate(sensitivities=…) against fourth-order central
differences of whole runs on the 7-DOF arm (x₀ along the tangent) and the double pendulum (a mass
moved in the scenario's text), `soadyn run` of a scenario with the key writing /sensitivities that
read_log gives back as simulate returned it, and the refusals."""
import os
import re

import numpy as np
import pytest

import soadyn
from conftest import ROOT, cli

ARM = os.path.join(ROOT, "tests", "data", "arm7.urdf")
PENDULUM = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
TIGHT = dict(method="cvode-adams", rtol=1e-11, atol=1e-13)


def tangent_difference(model, qa, va, qb, vb):
    """x_a − x_b along the tangent (revolute joints: the coordinates)"""
    assert model.nq == model.nv
    return np.concatenate([qa - qb, va - vb], axis=-1)


def stencil(run, h):
    """(8 (x(h) − x(−h)) − (x(2h) − x(−2h))) / 12h, run(a) -> (q, v) at every sample"""
    (q1, v1), (q_1, v_1), (q2, v2), (q_2, v_2) = run(h), run(-h), run(2 * h), run(-2 * h)
    return (8 * np.concatenate([q1 - q_1, v1 - v_1], -1) - np.concatenate([q2 - q_2, v2 - v_2], -1)) / (12 * h)


def test_initial_state_sensitivities_of_the_arm_match_central_differences():
    scene = soadyn.load_scenario(ARM)
    nv = scene.model.nv
    rng = np.random.default_rng(5)
    scene.q0 = rng.uniform(-0.5, 0.5, nv)  # inside the joints' limits for the whole run
    scene.v0 = rng.uniform(-0.5, 0.5, nv)
    q0, v0 = scene.q0, scene.v0
    traj = soadyn.simulate(scene, t_end=0.4, output_dt=0.1, sensitivities={"initial_state": True}, **TIGHT)
    S = traj.sensitivities
    assert S.initial_state.shape == (len(traj), 2 * nv, 2 * nv) and S.parameters is None
    assert S.state_names[0].startswith("q.") and S.state_names[nv].startswith("qd.")
    assert np.allclose(S.initial_state[0], np.eye(2 * nv), atol=1e-14)
    for k in (0, 3, nv + 1, 2 * nv - 1):  # a few columns: each is four runs
        def run(a):
            scene.q0, scene.v0 = q0, v0
            if k < nv:
                scene.q0 = q0 + a * np.eye(nv)[k]
            else:
                scene.v0 = v0 + a * np.eye(nv)[k - nv]
            t = soadyn.simulate(scene, t_end=0.4, output_dt=0.1, **TIGHT)
            return t.q, t.v
        want = stencil(run, 1e-3)
        got = S.initial_state[:, :, k]
        assert np.abs(got - want).max() <= 1e-6 * max(1.0, np.abs(want).max()), k
    scene.q0, scene.v0 = q0, v0


def test_parameter_sensitivity_matches_a_mass_changed_in_the_scenario():
    text = open(PENDULUM).read()
    scene = soadyn.parse_scenario(text, PENDULUM)
    traj = soadyn.simulate(scene, t_end=1.0, output_dt=0.25, sensitivities={"parameters": ["lower"]}, **TIGHT)
    S = traj.sensitivities
    assert S.parameter_names[:2] == ["lower.m", "lower.mcx"] and S.parameter_units[0] == "kg"
    # the lower link's mass, its centre of mass held: m and m c move together (c = (0, 0, −0.5)), and
    # the inertia about the joint point by m |c|² ... as soadyn.parameters says
    pi = soadyn.parameters(scene.model)[10:]
    lower = text.rindex("mass: 1.0")

    def run(a):
        moved = soadyn.parse_scenario(text[:lower] + f"mass: {1.0 + a!r}" + text[lower + len("mass: 1.0"):], PENDULUM)
        t = soadyn.simulate(moved, t_end=1.0, output_dt=0.25, **TIGHT)
        return t.q, t.v
    want = stencil(run, 1e-3)
    # d pi / d m along that change, from the parameters of the moved model
    heavier = soadyn.parse_scenario(text[:lower] + "mass: 2.0" + text[lower + len("mass: 1.0"):], PENDULUM)
    dpi = soadyn.parameters(heavier.model)[10:] - pi  # linear in m: m, m c, I_origin = I_c + m (|c|² e − c cᵀ)
    got = S.parameters @ dpi
    assert np.abs(got - want).max() <= 1e-6 * max(1.0, np.abs(want).max())


def test_soadyn_run_logs_what_simulate_returns(tmp_path):
    text = open(PENDULUM).read()
    text = re.sub(r"t_end: .*", "t_end: 0.5", text)
    text = text.replace("simulation:\n", "simulation:\n  sensitivities: {initial_state: true, parameters: all}\n")
    path = tmp_path / "sens.yaml"
    path.write_text(text)
    out = tmp_path / "sens.h5"
    p = cli("run", path, "-o", out)
    assert p.returncode == 0, p.stderr
    logged = soadyn.read_log(str(out))
    direct = soadyn.simulate(str(path))
    a, b = logged.sensitivities, direct.sensitivities
    assert a.initial_state.shape == (len(direct), 4, 4) and a.parameters.shape == (len(direct), 4, 20)
    assert np.allclose(a.initial_state, b.initial_state, rtol=1e-12, atol=1e-14)
    assert np.allclose(a.parameters, b.parameters, rtol=1e-12, atol=1e-14)
    assert a.parameter_names == b.parameter_names and a.state_units == ["rad", "rad", "rad/s", "rad/s"]
    import h5py
    with h5py.File(out, "r") as f:
        units = [u.decode() if isinstance(u, bytes) else u for u in f["sensitivities/parameters"].attrs["units"]]
        assert units[0] == "rad/kg" and len(units) == 4 * 20


def test_refusals_are_one_line(tmp_path):
    scene = soadyn.load_scenario(PENDULUM)
    with pytest.raises(soadyn.Error, match="CVODE method"):
        soadyn.simulate(scene, method="rk4", t_end=0.1, sensitivities={"initial_state": True})
    with pytest.raises(soadyn.Error, match="controller"):
        soadyn.simulate(scene, t_end=0.1, sensitivities={"initial_state": True}, controller=lambda t, q, v: np.zeros(2))
    with pytest.raises(soadyn.Error, match="did you mean 'lower'"):
        soadyn.simulate(scene, t_end=0.1, sensitivities={"parameters": ["lowr"]})
    with pytest.raises(soadyn.Error, match="did you mean 'initial_state'"):
        soadyn.simulate(scene, t_end=0.1, sensitivities={"initial_stat": True})
    out = tmp_path / "never.h5"
    with pytest.raises(soadyn.Error):
        soadyn.simulate(scene, method="rk4", t_end=0.1, output=str(out), sensitivities={"initial_state": True})
    assert not out.exists()
