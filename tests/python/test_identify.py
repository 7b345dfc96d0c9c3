"""soadyn.identify from Python: a run of tests/data/identify_arm.yaml fitted back from a scene with
the forearm 30 % off (a run file, a Trajectory and a dict of arrays give the same fit), the result's
fields (standard errors, rank, unidentifiable directions), the fitted model and scene, a fitted
model through pickle, and the refusals."""
import os
import pickle

import numpy as np
import pytest

import soadyn
from conftest import ROOT

ARM = os.path.join(ROOT, "tests", "data", "identify_arm.yaml")
I_CM = np.array([[0.041, 0.0005, -0.001], [0.0005, 0.040, 0.0008], [-0.001, 0.0008, 0.006]])


def start_scene():
    with open(ARM) as f:
        text = f.read()
    inertia = (0.7 * I_CM).tolist()
    return soadyn.parse_scenario(text + f"inertial:\n  forearm: {{mass: 1.3, com: [0.015, -0.01, 0.35], inertia: {inertia}}}\n",
                                 ARM)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("identify") / "arm.h5")
    traj = soadyn.simulate(ARM, output=path)
    return path, traj


def test_least_squares_from_a_run_file_a_trajectory_and_arrays(run):
    path, traj = run
    truth = soadyn.load(ARM)
    i = truth.body_index("forearm")
    pi = soadyn.parameters(truth)[10 * i:10 * i + 10]
    start = start_scene()
    r = soadyn.identify(start, path, ["forearm"])
    assert r.method == "least-squares" and r.rank == 10 and r.unidentifiable.shape == (10, 0)
    assert r.names[0] == "forearm.m" and r.units[0] == "kg"
    assert np.max(np.abs(r.fitted - pi) / np.maximum(np.abs(pi), 1e-3)) < 1e-6
    assert abs(r.prior[0] - 1.3) < 1e-12 and r.value("forearm.m") == pytest.approx(1.0, rel=1e-9)
    assert r.standard_errors.shape == (10,) and np.all(r.standard_errors < 1e-9)
    assert r.rms_prior > 1.0 and r.rms_fitted < 1e-8
    for data in (traj, {"t": traj.t, "q": traj.q, "v": traj.v, "qdd": traj.qdd}):
        assert np.array_equal(soadyn.identify(start, data, "forearm").fitted, r.fitted)
    # the fitted model and scene carry the fit; the model pickles bit for bit
    assert np.allclose(soadyn.parameters(r.scenario.model), soadyn.parameters(r.model), rtol=1e-14, atol=1e-16)
    assert r.scenario_text.startswith("# fitted by soadyn identify")
    assert np.array_equal(soadyn.parameters(pickle.loads(pickle.dumps(r.model))), soadyn.parameters(r.model))


def test_unidentifiable_directions_and_measured_torques(run):
    _, traj = run
    scene = soadyn.load_scenario(ARM)
    r = soadyn.identify(scene, traj, "all")
    assert r.rank == 15 and r.unidentifiable.shape == (30, 15)
    assert "turret.Ixx" in r.unidentifiable_text and "upper_arm.m" in r.unidentifiable_text
    # the same fit from the torques given as measurements
    tau = np.array([scene.inputs.evaluate(t, q, v) for t, q, v in zip(traj.t, traj.q, traj.v)])
    again = soadyn.identify(scene, traj, "all", tau=tau)
    assert np.allclose(again.fitted, r.fitted, rtol=1e-12, atol=1e-14)


def test_refusals(run):
    path, traj = run
    scene = soadyn.load_scenario(ARM)
    with pytest.raises(soadyn.Error, match="no body named 'forarm'; did you mean 'forearm'"):
        soadyn.identify(scene, path, ["forarm"])
    with pytest.raises(soadyn.Error, match="unknown key 'tau'"):
        soadyn.identify(scene, {"t": traj.t, "q": traj.q, "v": traj.v, "tau": traj.qdd}, "forearm")
    with pytest.raises(ValueError, match="method: expected 'auto', 'least-squares' or 'gauss-newton'"):
        soadyn.identify(scene, path, "forearm", method="newton")
    with pytest.raises(soadyn.Error, match="least squares needs the accelerations"):
        soadyn.identify(scene, {"t": traj.t, "q": traj.q, "v": traj.v}, "forearm", method="least-squares")
    with pytest.raises(soadyn.Error, match=r"q: expected 401 × 3 samples, got 401 × 2"):
        soadyn.identify(scene, {"t": traj.t, "q": traj.q[:, :2], "v": traj.v, "qdd": traj.qdd}, "forearm")
