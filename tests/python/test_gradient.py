"""Adjoint gradients from Python: soadyn.gradient with a Python terminal cost against the forward
sensitivities of the same run on the 7-DOF arm; a Python running cost against the library's
tracking cost of the same function (two codings of one G); tracking a run file by its path against
central differences of the cost; the callable's exception re-raised and bad returns refused."""
import os
import types

import numpy as np
import pytest

import soadyn
from conftest import ROOT

ARM = os.path.join(ROOT, "tests", "data", "arm7.urdf")
PENDULUM = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
TIGHT = dict(method="cvode-adams", rtol=1e-11, atol=1e-13)


def arm_scene():
    scene = soadyn.load_scenario(ARM)
    rng = np.random.default_rng(5)
    scene.q0 = rng.uniform(-0.5, 0.5, scene.model.nv)
    scene.v0 = rng.uniform(-0.2, 0.2, scene.model.nv)  # inside the joints' limits for the whole run
    return scene


def test_adjoint_matches_forward_sensitivities_on_the_arm():
    scene = arm_scene()
    nv = scene.model.nv
    c = np.random.default_rng(1).uniform(-1, 1, 2 * nv)

    def phi(q, v):  # Φ = cᵀ x(T) + ½ |x(T)|², arm: q is the tangent
        x = np.concatenate([q, v])
        g = c + x
        return c @ x + 0.5 * x @ x, g[:nv], g[nv:]

    g = soadyn.gradient(scene, soadyn.Cost(terminal=phi), t_end=0.3, **TIGHT)
    traj = soadyn.simulate(scene, t_end=0.3, output_dt=0.3, sensitivities={"initial_state": True, "parameters": "all"},
                           **TIGHT)
    x = np.concatenate([traj.q[-1], traj.v[-1]])
    dphi = c + x
    want0 = traj.sensitivities.initial_state[-1].T @ dphi
    wantp = traj.sensitivities.parameters[-1].T @ dphi
    assert g.initial_state.shape == (2 * nv,) and g.parameters.shape == (10 * scene.model.nbodies,)
    assert np.abs(g.initial_state - want0).max() <= 1e-6 * max(1.0, np.abs(want0).max())
    assert np.abs(g.parameters - wantp).max() <= 1e-6 * max(1.0, np.abs(wantp).max())
    assert g.parameter_names[:2] == [scene.model.body_names[0] + ".m", scene.model.body_names[0] + ".mcx"]
    assert g.stats["backward_steps"] > 0 and g.stats["checkpoints"] >= 0
    assert g.cost == pytest.approx(c @ x + 0.5 * x @ x, rel=1e-9)


def test_a_python_running_cost_equals_the_same_tracking_cost():
    scene = soadyn.load_scenario(PENDULUM)
    model = scene.model
    # the reference: the pendulum at rest at q = (0.3, −0.2), so q̂(t) is that constant
    t = np.linspace(0.0, 1.0, 11)
    ref_q = np.tile([0.3, -0.2], (len(t), 1))
    ref = types.SimpleNamespace(t=t, q=ref_q, v=np.zeros((len(t), 2)))  # anything with t, q and v
    library = soadyn.tracking_cost(model, ref, q=[2.0, 3.0], v=0.5)
    w = np.array([2.0, 3.0])

    def running(t, q, v):
        e = q - ref_q[0]
        return 0.5 * e @ (w * e) + 0.25 * v @ v, w * e, 0.5 * v

    a = soadyn.gradient(scene, library, t_end=1.0, **TIGHT)
    b = soadyn.gradient(scene, soadyn.Cost(running=running), t_end=1.0, **TIGHT)
    assert a.cost == pytest.approx(b.cost, rel=1e-9)
    assert np.allclose(a.initial_state, b.initial_state, rtol=1e-8, atol=1e-10)
    assert np.allclose(a.parameters, b.parameters, rtol=1e-8, atol=1e-10)


def test_tracking_a_run_file_matches_central_differences(tmp_path):
    scene = soadyn.load_scenario(PENDULUM)
    run = str(tmp_path / "reference.h5")
    other = soadyn.load_scenario(PENDULUM)
    other.v0 = np.array([0.2, -0.1])
    soadyn.simulate(other, t_end=1.0, output_dt=0.01, output=run, **TIGHT)
    cost = soadyn.tracking_cost(scene.model, run, q=1.0, v=0.1)
    g = soadyn.gradient(scene, cost, wrt="initial_state", t_end=1.0, **TIGHT)
    assert g.parameters is None and len(g.state_names) == 4
    v0 = scene.v0.copy()

    def G(a, k):
        scene.v0 = v0 + a * np.eye(2)[k]
        return soadyn.gradient(scene, cost, wrt="initial_state", t_end=1.0, **TIGHT).cost

    h = 1e-3
    for k in range(2):
        fd = (8 * (G(h, k) - G(-h, k)) - (G(2 * h, k) - G(-2 * h, k))) / (12 * h)
        assert g.initial_state[2 + k] == pytest.approx(fd, rel=1e-6, abs=1e-8)  # |∂G/∂v₀| ~ 1e-3 here
    scene.v0 = v0


def test_the_callables_exception_is_reraised_and_bad_returns_refused():
    scene = soadyn.load_scenario(PENDULUM)

    class Boom(Exception):
        pass

    def raising(q, v):
        raise Boom("from the cost")

    with pytest.raises(Boom, match="from the cost"):
        soadyn.gradient(scene, soadyn.Cost(terminal=raising), t_end=0.2)
    with pytest.raises(soadyn.Error, match=r"must return a tuple \(value, d/dq, d/dv\)"):
        soadyn.gradient(scene, soadyn.Cost(terminal=lambda q, v: 1.0), t_end=0.2)
    with pytest.raises(soadyn.Error, match=r"d/dq must have shape \(2,\)"):
        soadyn.gradient(scene, soadyn.Cost(terminal=lambda q, v: (1.0, np.zeros(3), np.zeros(2))), t_end=0.2)
    with pytest.raises(soadyn.Error, match="need a CVODE method"):
        soadyn.gradient(scene, soadyn.Cost(terminal=lambda q, v: (0.0, q, v)), method="rk4", t_end=0.2)
    with pytest.raises(soadyn.Error, match="wrt: expected"):
        soadyn.gradient(scene, soadyn.Cost(terminal=lambda q, v: (0.0, q, v)), wrt="mass")
    with pytest.raises(soadyn.Error, match="did you mean 'lower'"):
        soadyn.gradient(scene, soadyn.Cost(terminal=lambda q, v: (0.0, q, v)), parameters=["lowr"], t_end=0.2)
