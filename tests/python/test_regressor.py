"""The inertial-parameter regressor from Python: Y @ parameters(model) is inverse dynamics, a model
with other parameters obeys the same Y, dqdd/dpi against central differences, bad pi refused."""
import os

import numpy as np
import pytest

import soadyn
from conftest import ROOT

ARM = os.path.join(ROOT, "tests", "data", "arm7.urdf")


def test_regressor_times_parameters_is_inverse_dynamics_and_fits_a_payload():
    model = soadyn.load(ARM)
    data = model.create_data()
    rng = np.random.default_rng(2)
    pi = soadyn.parameters(model)
    assert pi.shape == (10 * model.nbodies,)
    # the hand 10 % heavier (mass and inertia scale together, the centre of mass stays)
    heavy = pi.copy()
    heavy[-10:] *= 1.1
    heavier = soadyn.with_parameters(model, heavy)
    rows, taus = [], []
    for _ in range(30):
        q, v, qdd = rng.uniform(-1, 1, model.nq), rng.uniform(-1, 1, model.nv), rng.uniform(-2, 2, model.nv)
        Y = soadyn.regressor(model, data, q, v, qdd)
        tau = soadyn.inverse_dynamics(model, data, q, v, qdd).copy()
        assert np.allclose(Y @ pi, tau, rtol=1e-12, atol=1e-12)
        rows.append(Y)
        taus.append(soadyn.inverse_dynamics(heavier, heavier.create_data(), q, v, qdd).copy())
    # identification: the hand's ten parameters from the heavier robot's torques, the rest known
    Y = np.vstack(rows)
    known = Y[:, :-10] @ pi[:-10]
    fit, *_ = np.linalg.lstsq(Y[:, -10:], np.concatenate(taus) - known, rcond=None)
    assert np.allclose(fit, heavy[-10:], rtol=1e-8, atol=1e-12)


def test_parameter_derivative_and_refusals():
    model = soadyn.load(ARM)
    data = model.create_data()
    q, v, tau = np.full(model.nq, 0.2), np.full(model.nv, 0.3), np.full(model.nv, 0.5)
    D = soadyn.forward_dynamics_parameter_derivative(model, data, q, v, tau)
    pi = soadyn.parameters(model)
    j = 10 * (model.nbodies - 1)  # the hand's mass
    h = 1e-6
    up, dn = pi.copy(), pi.copy()
    up[j] += h
    dn[j] -= h
    def qdd(p):
        m = soadyn.with_parameters(model, p)
        return soadyn.forward_dynamics(m, m.create_data(), q, v, tau).copy()
    fd = (qdd(up) - qdd(dn)) / (2 * h)
    assert np.allclose(D[:, j], fd, rtol=1e-5, atol=1e-8)
    bad = pi.copy()
    bad[10] = -1.0
    with pytest.raises(soadyn.Error, match=f"body '{model.body_names[1]}': mass"):
        soadyn.with_parameters(model, bad)
