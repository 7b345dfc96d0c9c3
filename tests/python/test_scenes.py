"""The scenes where methods break, checked against what is known of them in closed form.

tumbling_t_handle: Euler's equations of a torque-free body have an exact solution in Jacobi
elliptic functions (Landau & Lifshitz, Mechanics, §37).  The body-frame ω₂ is proportional to
sn(τ, k), τ = p t, so the handle flips over (ω₂ changes sign) every 2 K(k) / p.
flexible_satellite: no external force or torque, so linear and angular momentum stay constant
whatever the springs and dampers do inside."""
import math
import os

import numpy as np

import soadyn
from conftest import SCENARIOS


def elliptic_k(m):
    """K(m) = ∫₀^{π/2} dθ / √(1 − m sin²θ), by the arithmetic-geometric mean: π / (2 AGM(1, √(1 − m)))"""
    a, b = 1.0, math.sqrt(1.0 - m)
    while abs(a - b) > 1e-16 * a:
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


def body_rates(q, w_inertial):
    """ω in body axes, Cᵀ ω, from the attitude quaternions [qw qx qy qz] (body → inertial)"""
    out = np.empty_like(w_inertial)
    for k, ((w, x, y, z), om) in enumerate(zip(q, w_inertial)):
        C = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        out[k] = C.T @ om
    return out


def test_t_handle_flips_with_the_elliptic_period():
    # the scene with a larger initial wobble (0.05 rad/s, not 0.001): so far from the separatrix
    # the period depends on E and L² only mildly, and the integrator's 1e-10 in E moves it by 1e-8
    path = os.path.join(SCENARIOS, "tumbling_t_handle.yaml")
    text = open(path).read()
    assert "qd: {handle: [0.001, 6.0," in text
    scene = soadyn.parse_scenario(text.replace("qd: {handle: [0.001, 6.0,", "qd: {handle: [0.05, 6.0,"), path)
    I1, I2, I3 = np.diag(scene.model.inertias[0])
    w0 = scene.v0[:3]  # inertial = body axes at the start (identity attitude)
    assert np.allclose(scene.q0[3:7], [1, 0, 0, 0])
    two_E = I1 * w0[0] ** 2 + I2 * w0[1] ** 2 + I3 * w0[2] ** 2
    L2 = (I1 * w0[0]) ** 2 + (I2 * w0[1]) ** 2 + (I3 * w0[2]) ** 2
    assert L2 < two_E * I2, "the polhode circles the I1 axis: Landau's formulas with axes 1 and 3 swapped"
    p = math.sqrt((I2 - I1) * (two_E * I3 - L2) / (I1 * I2 * I3))
    m = (I3 - I2) * (L2 - two_E * I1) / ((I2 - I1) * (two_E * I3 - L2))
    half_period = 2.0 * elliptic_k(m) / p

    traj = soadyn.simulate(scene, "cvode-adams", rtol=1e-11, atol=1e-13, t_end=30.0, output_dt=1e-3)
    assert traj.summary.completed
    w2 = body_rates(traj.q[:, 3:7], traj.v[:, :3])[:, 1]
    k = np.nonzero(np.sign(w2[1:]) != np.sign(w2[:-1]))[0]
    # the crossings, by linear interpolation between samples 1 ms apart (ω₂ is steep there)
    crossings = traj.t[k] - w2[k] * (traj.t[k + 1] - traj.t[k]) / (w2[k + 1] - w2[k])
    assert len(crossings) >= 4, crossings
    spacing = np.diff(crossings)
    assert np.all(np.abs(spacing - half_period) < 1e-6 * half_period), (spacing, half_period)
    # energy and |L| along the way
    assert traj.summary.max_energy_balance_error < 1e-9
    L = traj.angular_momentum
    assert np.max(np.abs(L - L[0])) < 1e-9 * np.linalg.norm(L[0])


def test_flexible_satellite_keeps_its_momentum():
    path = os.path.join(SCENARIOS, "flexible_satellite.yaml")
    traj = soadyn.simulate(path, "cvode-bdf", rtol=1e-9, atol=1e-11, t_end=2.0)
    assert traj.summary.completed
    p, h = traj.linear_momentum, traj.angular_momentum
    # the momentum the whole mass would have with all the kinetic energy: √(2 m T)
    scale_p = math.sqrt(2.0 * sum(soadyn.load(path).masses) * np.max(traj.kinetic_energy))
    assert np.max(np.linalg.norm(h - h[0], axis=1)) < 1e-7 * np.linalg.norm(h[0])
    assert np.max(np.linalg.norm(p - p[0], axis=1)) < 1e-7 * scale_p
    # the dampers take energy out and never put it in: E falls (to the integrator's tolerance)
    E = traj.total_energy
    assert np.all(np.diff(E) < 1e-7 * abs(E[0])) and E[-1] < E[0]
