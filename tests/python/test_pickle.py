"""pickle and copy.deepcopy of Model and Data: the copy computes the same 𝓜, bias, frame poses and
potential energy to the last bit (same arithmetic on the same numbers), carries the same names,
limits, frames and warnings; a spawned worker process gets the same 𝓜; a foreign or corrupted state
is refused with one soadyn.Error."""
import copy
import multiprocessing
import os
import pickle

import numpy as np
import pytest

import soadyn
from conftest import ROOT, SCENARIOS, random_tree_yaml

ARM_FIXED = os.path.join(ROOT, "tests", "data", "frames", "arm_fixed.urdf")
MJCF_ARM = os.path.join(ROOT, "tests", "data", "mjcf", "arm.xml")


def models(rng):
    arm = soadyn.load(ARM_FIXED)                      # a URDF arm with links welded by fixed joints
    arm.add_frame("tool_tip", arm.frame_names[-1], [0.0, 0.0, 0.05], [0.1, 0.2, 0.3])
    out = [("arm_fixed.urdf", arm),
           ("satellite (free root)", soadyn.load(os.path.join(SCENARIOS, "satellite_two_arrays.yaml"))),
           ("screw_lift (helical joint)", soadyn.load(os.path.join(SCENARIOS, "screw_lift.yaml"))),
           ("random tree, free root, every joint kind",
            soadyn.parse_scenario(random_tree_yaml(rng, 8, free_root=True, fixed=2)).model)]
    # a fitted model: inertias about the origin set directly by with_parameters
    pi = soadyn.parameters(arm)
    out.append(("with_parameters", soadyn.with_parameters(arm, pi * np.repeat(rng.uniform(0.8, 1.2, arm.nbodies), 10))))
    if os.path.exists(MJCF_ARM):
        try:
            out.append(("mjcf arm.xml", soadyn.load(MJCF_ARM)))
        except soadyn.Error as e:  # a build without MuJoCo's compiler
            assert "MJCF" in str(e) or "MuJoCo" in str(e), e
    return out


def fields(model):
    return dict(nq=model.nq, nv=model.nv, nbodies=model.nbodies, body_names=model.body_names,
                joint_names=model.joint_names, joint_types=model.joint_types, parents=model.parents,
                q_names=model.q_names, v_names=model.v_names, lower=model.lower, upper=model.upper,
                frame_names=model.frame_names, frame_bodies=model.frame_bodies, warnings=model.warnings,
                depth=model.depth)


def same_numbers(a, b, rng):
    """a and b compute bit-identical results at seeded random states"""
    assert fields(a) == fields(b)
    for name in ("gravity", "masses", "coms", "inertias", "axes", "pitches"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.array_equal(soadyn.parameters(a), soadyn.parameters(b))
    da, db = a.create_data(), b.create_data()
    for _ in range(5):
        q = a.normalize(rng.uniform(-1.5, 1.5, a.nq))
        v = rng.uniform(-2, 2, a.nv)
        assert np.array_equal(soadyn.mass_matrix(a, da, q), soadyn.mass_matrix(b, db, q))
        assert np.array_equal(soadyn.bias_forces(a, da, q, v), soadyn.bias_forces(b, db, q, v))
        assert soadyn.potential_energy(a, da, q) == soadyn.potential_energy(b, db, q)
        for f in a.frame_names:
            for x, y in zip(soadyn.frame_placement(a, da, q, f), soadyn.frame_placement(b, db, q, f)):
                assert np.array_equal(x, y), f


def test_pickle_copy_and_deepcopy_reproduce_the_model(rng):
    for name, model in models(rng):
        for clone in (pickle.loads(pickle.dumps(model)), copy.deepcopy(model), copy.copy(model)):
            assert clone is not model
            same_numbers(model, clone, np.random.default_rng(7))
    # the copy is independent: a frame added to it is not the original's
    arm = soadyn.load(ARM_FIXED)
    clone = copy.deepcopy(arm)
    clone.add_frame("extra", "world")
    assert "extra" in clone.frame_names and "extra" not in arm.frame_names


def test_a_loaded_models_warnings_and_limits_travel():
    model = soadyn.load(os.path.join(SCENARIOS, "panda_like.urdf"))
    clone = pickle.loads(pickle.dumps(model))
    assert clone.lower == model.lower and clone.upper == model.upper
    assert np.isfinite(model.lower).any()
    assert clone.warnings == model.warnings


def test_data_round_trip_keeps_model_and_results(rng):
    model = soadyn.load(ARM_FIXED)
    data = model.create_data()
    q, v = rng.uniform(-1, 1, model.nq), rng.uniform(-1, 1, model.nv)
    soadyn.mass_matrix(model, data, q)
    soadyn.bias_forces(model, data, q, v)
    soadyn.forward_dynamics(model, data, q, v, rng.uniform(-1, 1, model.nv))
    for clone in (pickle.loads(pickle.dumps(data)), copy.deepcopy(data), copy.copy(data)):
        for name in ("M", "bias", "qdd", "R", "eta", "d", "s", "r", "G", "V", "Vbar"):
            assert np.array_equal(getattr(clone, name), getattr(data, name)), name
        # the copy owns its arrays: computing on it leaves the original's alone
        M = data.M.copy()
        soadyn.mass_matrix(clone.model, clone, np.zeros(model.nq))
        assert np.array_equal(data.M, M)
        same_numbers(model, clone.model, np.random.default_rng(3))
    assert copy.copy(data).model is model                     # a shallow copy shares the model
    memo = {}
    deep = copy.deepcopy([model, data], memo)
    assert deep[1].model is deep[0] and deep[0] is not model  # deepcopy keeps the sharing


def mass_matrix_in_worker(model, q):
    return soadyn.mass_matrix(model, model.create_data(), q).copy()


def test_a_spawned_worker_computes_the_same_mass_matrix(rng):
    model = soadyn.load(ARM_FIXED)
    fitted = soadyn.with_parameters(model, soadyn.parameters(model) * 1.1)
    q = rng.uniform(-1, 1, model.nq)
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        M = pool.apply(mass_matrix_in_worker, (fitted, q))
    assert np.array_equal(M, soadyn.mass_matrix(fitted, fitted.create_data(), q))


def test_foreign_and_corrupted_states_are_refused():
    model = soadyn.load(ARM_FIXED)
    tag, version, fields_ = model.__getstate__()
    assert (tag, version) == ("soadyn.Model", 1)
    bad = [
        (("soadyn.Model", 2, fields_), "state version 2: this soadyn reads version 1 only"),
        (("numpy.ndarray", 1, fields_), "expected the tag 'soadyn.Model'"),
        ("not a tuple", "expected a (tag, version, fields) tuple"),
        (("soadyn.Model", 1, {k: v for k, v in fields_.items() if k != "mass"}), "state field 'mass': missing"),
        (("soadyn.Model", 1, {**fields_, "mass": "heavy"}), "state field 'mass': wrong type"),
        (("soadyn.Model", 1, {**fields_, "mass": fields_["mass"][:-1]}), "state field 'mass': expected"),
        (("soadyn.Model", 1, {**fields_, "mass": [-1.0] * len(fields_["mass"])}), "mass"),
        (("soadyn.Model", 1, {**fields_, "parent": [0] * len(fields_["parent"])}), "state field 'parent'"),
    ]
    for state, message in bad:
        clone = soadyn.Model.__new__(soadyn.Model)
        with pytest.raises(soadyn.Error, match=None) as e:
            clone.__setstate__(state)
        assert message in str(e.value), (message, str(e.value))
        assert "\n" not in str(e.value)
    data = model.create_data()
    tag, version, f = data.__getstate__()
    with pytest.raises(soadyn.Error, match="state field 'M': expected"):
        soadyn.Data.__new__(soadyn.Data).__setstate__((tag, version, {**f, "M": np.zeros(3)}))
    with pytest.raises(soadyn.Error, match="state field 'model': expected a soadyn.Model"):
        soadyn.Data.__new__(soadyn.Data).__setstate__((tag, version, {**f, "model": 3}))


def simulate_in_worker(scene):
    return soadyn.simulate(scene).q


def test_scenarios_round_trip_and_run_the_same(rng):
    """torques and dampers (driven_pendulum), controllers and limits (arm_control_limits), a URDF
    robot with table targets (panda_gripper), a free body (tumbling_t_handle): the copy's run is the
    original's to the bit, with q0, v0 and settings changed before pickling"""
    for name in ("driven_pendulum", "arm_control_limits", "panda_gripper", "tumbling_t_handle"):
        scene = soadyn.load_scenario(os.path.join(SCENARIOS, name + ".yaml"))
        if not np.isfinite(scene.model.lower).any():  # away from a limit the scene starts at
            scene.q0 = scene.model.normalize(scene.q0 + rng.uniform(-0.05, 0.05, scene.model.nq))
        scene.v0 = scene.v0 + rng.uniform(-0.1, 0.1, scene.model.nv)
        scene.settings.t_end = 0.2
        scene.settings.rtol = 1e-9
        for clone in (pickle.loads(pickle.dumps(scene)), copy.deepcopy(scene)):
            assert (clone.name, clone.path, clone.text) == (scene.name, scene.path, scene.text)
            assert np.array_equal(clone.q0, scene.q0) and np.array_equal(clone.v0, scene.v0)
            assert len(clone.inputs) == len(scene.inputs)
            a, b = soadyn.simulate(scene), soadyn.simulate(clone)
            assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v), name
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "driven_pendulum.yaml"))
    scene.settings.t_end = 0.5
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        q = pool.apply(simulate_in_worker, (scene,))
    assert np.array_equal(q, soadyn.simulate(scene).q)
    tag, version, f = scene.__getstate__()
    bad = soadyn.Scenario.__new__(soadyn.Scenario)
    with pytest.raises(soadyn.Error, match="state field 'torques': an index 7 outside 0..1"):
        bad.__setstate__((tag, version, {**f, "torques": [("shoulder", 7, 0.0, 1.0, 1.0, 0.0)]}))
    with pytest.raises(soadyn.Error, match="state field 'q0': expected 2 entries, got 1"):
        bad.__setstate__((tag, version, {**f, "q0": [0.0]}))
