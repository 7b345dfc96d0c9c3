"""The module against the C++ library (through `soadyn inspect --json`), against the note's closed
forms, against itself by independent routes, and its stated memory sharing, stubs and help."""
import ast
import dataclasses
import gc
import os
import pydoc
import re

import numpy as np
import pytest

import soadyn
from conftest import ROOT, SCENARIOS, assert_close, inspect_json, random_tree_yaml


def skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def rot(axis, angle):
    K = skew(np.asarray(axis, float) / np.linalg.norm(axis))
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def random_state(rng, model):
    q = model.normalize(rng.uniform(-2, 2, model.nq))
    return q, rng.uniform(-1, 1, model.nv), rng.uniform(-3, 3, model.nv)


# ---- Python equals C++ ----------------------------------------------------------------------

@pytest.mark.parametrize("free_root", [False, True])
def test_random_trees_equal_the_cpp_library(tmp_path, rng, free_root):
    for trial in range(6):
        n = int(rng.integers(1, 12))
        path = tmp_path / f"tree{trial}.yaml"
        path.write_text(random_tree_yaml(rng, n, free_root=free_root))
        model = soadyn.load(str(path))
        data = model.create_data()
        q, v, tau = random_state(rng, model)
        for method in ("aba", "dense", "sparse", "on"):  # "on": the old word for aba
            ref = inspect_json(str(path), q, v, tau, method=method)
            q = np.array(ref["q"])  # as the command line normalized it
            assert ref["joints"] == model.joint_names
            assert (ref["nq"], ref["nv"]) == (model.nq, model.nv)
            assert_close(soadyn.mass_matrix(model, data, q), ref["M"], 1e-14)
            assert_close(soadyn.bias_forces(model, data, q, v), ref["bias"], 1e-14)
            assert_close(soadyn.forward_dynamics(model, data, q, v, tau, method=method), ref["qdd"], 1e-14)
            assert_close(soadyn.kinetic_energy(model, data, q, v), ref["kinetic_energy"], 1e-14)
            assert_close(soadyn.potential_energy(model, data, q), ref["potential_energy"], 1e-14)
            lin, ang = soadyn.momentum(model, data, q, v)
            assert_close(lin, ref["momentum"]["linear"], 1e-14)
            assert_close(ang, ref["momentum"]["angular"], 1e-14)
            assert_close(model.gravity, ref["gravity"], 0)


def test_independent_routes_agree(tmp_path, rng):
    """inverse ∘ forward dynamics, the literal procedure, 𝓜⁻¹ 𝓜 = e, Jᵀ M̄ J, ½ vᵀ𝓜v and Σ m ṙ from Python"""
    for trial in range(5):
        path = tmp_path / f"tree{trial}.yaml"
        path.write_text(random_tree_yaml(rng, int(rng.integers(2, 15)), free_root=trial % 2 == 1))
        model = soadyn.load(str(path))
        data = model.create_data()
        q, v, tau = random_state(rng, model)
        M = soadyn.mass_matrix(model, data, q).copy()
        assert_close(soadyn.mass_matrix_literal(model, data, q), M, 1e-12)
        assert_close(soadyn.minverse(model, data, q) @ M, np.eye(model.nv), 1e-10)  # the articulated-body 𝓜⁻¹
        qdd = soadyn.forward_dynamics(model, data, q, v, tau).copy()
        assert_close(soadyn.inverse_dynamics(model, data, q, v, qdd), tau, 1e-10)
        assert_close(M @ qdd + soadyn.bias_forces(model, data, q, v), tau, 1e-10)
        # 𝓜 = Jᵀ diag(M̄_i) J with M̄_i = [R I_cm Rᵀ, 0; 0, m e], from the model's and data's arrays
        J = soadyn.jacobian(model, data, q)
        assert J.shape == (6 * model.nbodies, model.nv)
        Mbar = np.zeros((6 * model.nbodies,) * 2)
        for i, (m, I, R) in enumerate(zip(model.masses, model.inertias, data.R)):
            Mbar[6 * i:6 * i + 3, 6 * i:6 * i + 3] = R @ I @ R.T
            Mbar[6 * i + 3:6 * i + 6, 6 * i + 3:6 * i + 6] = m * np.eye(3)
        assert_close(J.T @ Mbar @ J, M, 1e-12)
        assert_close(soadyn.kinetic_energy(model, data, q, v), 0.5 * v @ M @ v, 1e-12)
        rdot = (J @ v).reshape(-1, 6)[:, 3:]
        assert_close(soadyn.momentum(model, data, q, v)[0], model.masses @ rdot, 1e-12)
        # the data's views after update_velocities: v̄_i = J_i v, r_i = η_i + s_i
        soadyn.update_velocities(model, data, q, v)
        assert_close(data.Vbar, (J @ v).reshape(-1, 6), 1e-12)
        assert_close(data.r, data.eta + data.s, 1e-14)


def _chain_urdf(n):
    """n links in series, continuous joints about z, y, x in turn, each 0.3 along its parent's x"""
    axes = ("0 0 1", "0 1 0", "1 0 0")
    links = "".join(f'<link name="l{i}"><inertial><origin xyz="0.15 0 0"/><mass value="1"/>'
                    f'<inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                    for i in range(1, n + 1))
    joints = "".join(f'<joint name="j{i}" type="continuous"><parent link="l{i - 1}"/><child link="l{i}"/>'
                     f'<origin xyz="{0.3 if i > 1 else 0} 0 0"/><axis xyz="{axes[(i - 1) % 3]}"/></joint>'
                     for i in range(1, n + 1))
    return f'<robot name="chain{n}"><link name="l0"/>{links}{joints}</robot>'


def test_state_only_routes_equal_the_staged_ones(tmp_path, rng):
    """kinematics=False (the C++ entry points from the state alone, in body axes) against the default
    staged calls: random trees of every joint type (a planar one makes the bias staged anyway), the
    7-DOF arm's URDF (joints along unit axes: the turned fast path), and chains of 12 and 30 (the
    all-local 𝓜 and, past depth 22, the mixed route)"""
    models = [soadyn.load(os.path.join(ROOT, "tests", "data", "arm7.urdf"))]
    for n in (12, 30):
        path = tmp_path / f"chain{n}.urdf"
        path.write_text(_chain_urdf(n))
        models.append(soadyn.load(str(path)))
    for trial in range(4):
        path = tmp_path / f"tree{trial}.yaml"
        path.write_text(random_tree_yaml(rng, int(rng.integers(2, 15)), free_root=trial % 2 == 1))
        models.append(soadyn.load(str(path)))
    for model in models:
        data = model.create_data()
        for _ in range(3):
            q, v, _tau = random_state(rng, model)
            M = soadyn.mass_matrix(model, data, q).copy()
            b = soadyn.bias_forces(model, data, q, v).copy()
            assert_close(soadyn.mass_matrix(model, data, q, kinematics=False), M, 1e-12)
            assert_close(soadyn.bias_forces(model, data, q, v, kinematics=False), b, 1e-12)
            assert_close(soadyn.mass_matrix(model, data, q, kinematics=True), M, 0)
    # the route taken is the state-only one: on the arm (depth 7) it forms no inertial frame, so
    # data.R still holds what update_kinematics left (unspecified by the API, but a staged call
    # would have overwritten it)
    data = models[0].create_data()
    q = models[0].neutral()
    soadyn.update_kinematics(models[0], data, q)
    R0 = data.R.copy()
    q1, v1, _ = random_state(rng, models[0])
    soadyn.mass_matrix(models[0], data, q1, kinematics=False)
    soadyn.bias_forces(models[0], data, q1, v1, kinematics=False)
    assert_close(data.R, R0, 0)
    soadyn.mass_matrix(models[0], data, q1)
    assert np.abs(data.R - R0).max() > 1e-3
    with pytest.raises(TypeError, match="kinematics: expected True or False, got int"):
        soadyn.mass_matrix(models[0], data, q, kinematics=0)
    with pytest.raises(TypeError, match="missing required argument 'v'"):
        soadyn.bias_forces(models[0], data, q, kinematics=False)
    with pytest.raises(soadyn.Error, match="v"):  # sizes checked as the staged call does
        soadyn.bias_forces(models[0], data, q, np.zeros(3), kinematics=False)


# ---- the note's examples in closed form ------------------------------------------------------

def test_pendulum_on_cart(rng):
    model = soadyn.load(f"{SCENARIOS}/pendulum_on_cart.yaml")
    data = model.create_data()
    m1, m2, L, Izz = 2.0, 1.0, 1.0, 0.0834
    for _ in range(20):
        x, th = rng.uniform(-3, 3, 2)
        M = soadyn.mass_matrix(model, data, [x, th])
        assert_close(M, [[m1 + m2, m2 * L * np.cos(th)], [m2 * L * np.cos(th), Izz + m2 * L * L]], 1e-12)


def test_double_pendulum(rng):
    model = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    data = model.create_data()
    m, l1, c, J = 1.0, 1.0, 0.5, 0.0834
    for _ in range(20):
        t1, t2 = rng.uniform(-3, 3, 2)
        M11 = 2 * J + m * c * c + m * (l1 * l1 + c * c + 2 * l1 * c * np.cos(t2))
        M12 = J + m * (c * c + l1 * c * np.cos(t2))
        assert_close(soadyn.mass_matrix(model, data, [t1, t2]), [[M11, M12], [M12, J + m * c * c]], 1e-12)


def test_three_link_arm(rng):
    """(P7) with the hinge axis read as C_1 e_x (see tests/algorithm/test_mass_matrix.cpp)"""
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    ex, ez = np.eye(3)[0], np.eye(3)[2]
    m = [5.0, 2.0, 1.0]
    Ib = [np.diag([0.05, 0.05, 0.04]), np.diag([0.107, 0.107, 0.002]), np.diag([0.041, 0.041, 0.001])]
    com = [np.array([0, 0, 0.1]), np.array([0, 0, 0.4]), np.array([0, 0, 0.35])]
    d2, d3 = np.array([0, 0, 0.2]), np.array([0, 0, 0.8])
    S = skew
    qs, etas, Rs = [], [], []
    for _ in range(20):
        q = rng.uniform(-3, 3, 3)
        R1 = rot(ez, q[0]); R2 = R1 @ rot(ex, q[1]); R3 = R2 @ rot(ex, q[2])
        R = [R1, R2, R3]
        eta = [np.zeros(3), R1 @ d2, R1 @ d2 + R2 @ d3]
        s = [R[j] @ com[j] for j in range(3)]
        r = [eta[j] + s[j] for j in range(3)]
        I = [R[j] @ Ib[j] @ R[j].T for j in range(3)]
        e, E2 = R1 @ ex, S(eta[1])
        A11 = sum(I[j] - m[j] * S(r[j]) @ S(r[j]) for j in range(3))
        A12 = sum(I[j] - m[j] * S(r[j]) @ (S(r[j]) - E2) for j in (1, 2))
        A22 = sum(I[j] - m[j] * (S(r[j]) - E2) @ (S(r[j]) - E2) for j in (1, 2))
        S3 = S(s[2])
        M = np.array([[ez @ A11 @ ez, ez @ A12 @ e, ez @ (I[2] - m[2] * S(r[2]) @ S3) @ e],
                      [0, e @ A22 @ e, e @ (I[2] - m[2] * (S(r[2]) - E2) @ S3) @ e],
                      [0, 0, e @ (I[2] - m[2] * S3 @ S3) @ e]])
        M = np.triu(M) + np.triu(M, 1).T
        assert_close(soadyn.mass_matrix(model, data, q), M, 1e-12)
        assert_close(data.R, np.array(R), 1e-14)
        assert_close(data.eta, np.array(eta), 1e-14)
        qs.append(q), etas.append(eta), Rs.append(R)
    positions, rotations = soadyn.body_poses(model, np.array(qs))
    assert positions.shape == (20, 3, 3) and rotations.shape == (20, 3, 3, 3)
    assert_close(positions, np.array(etas), 1e-14)
    assert_close(rotations, np.array(Rs), 1e-14)
    one = soadyn.body_poses(model, qs[3])
    assert np.array_equal(one[0], positions[3]) and np.array_equal(one[1], rotations[3])
    with pytest.raises(soadyn.Error, match=r"body_poses: q: expected shape \(3,\) or \(T, 3\), got \(2, 2\)"):
        soadyn.body_poses(model, np.zeros((2, 2)))


def test_satellite_two_arrays(rng):
    scene = soadyn.load_scenario(f"{SCENARIOS}/satellite_two_arrays.yaml")
    model = scene.model
    data = model.create_data()
    assert (model.nq, model.nv) == (9, 8)
    assert model.q_names[:7] == ["bus.x", "bus.y", "bus.z", "bus.qw", "bus.qx", "bus.qy", "bus.qz"]
    assert model.v_names[:6] == ["bus.wx", "bus.wy", "bus.wz", "bus.vx", "bus.vy", "bus.vz"]
    ex = np.eye(3)[0]
    mb, ma = 500.0, 20.0
    Ib, Ia = np.diag([400.0, 350.0, 300.0]), np.diag([15.01, 3.76, 18.75])
    for _ in range(10):
        pos = rng.uniform(-5, 5, 3)
        qu = rng.normal(size=4)
        qu /= np.linalg.norm(qu)
        a2, a3 = rng.uniform(-3, 3, 2)
        q = np.array([*pos, *qu, a2, a3])
        w, x, y, z = qu
        R1 = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                       [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                       [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        e = R1 @ ex
        R = [R1, R1 @ rot(ex, a2), R1 @ rot(ex, a3)]
        d = [np.zeros(3), R1 @ [0, 1.0, 0], R1 @ [0, -1.0, 0]]
        s = [np.zeros(3), R[1] @ [0, 2.0, 0], R[2] @ [0, -2.0, 0]]
        mass = [mb, ma, ma]
        I = [R[0] @ Ib @ R[0].T, R[1] @ Ia @ R[1].T, R[2] @ Ia @ R[2].T]
        r = [d[j] + s[j] for j in range(3)]
        mbar = sum(mass)
        c = sum(mass[j] * r[j] for j in range(3)) / mbar
        M = np.zeros((8, 8))
        M[:3, :3] = sum(I[j] - mass[j] * skew(r[j]) @ skew(r[j]) for j in range(3))
        M[:3, 3:6] = mbar * skew(c)
        M[3:6, :3] = -mbar * skew(c)
        M[3:6, 3:6] = mbar * np.eye(3)
        for j in (1, 2):
            k = 5 + j
            M[:3, k] = (I[j] - mass[j] * skew(r[j]) @ skew(s[j])) @ e
            M[3:6, k] = -mass[j] * skew(s[j]) @ e
            M[k, :3] = e @ (I[j] - mass[j] * skew(s[j]) @ skew(r[j]))
            M[k, 3:6] = e @ (mass[j] * skew(s[j]))
            M[k, k] = e @ (I[j] - mass[j] * skew(s[j]) @ skew(s[j])) @ e
        assert_close(soadyn.mass_matrix(model, data, q), M, 1e-12)


def test_model_methods():
    scene = soadyn.load_scenario(f"{SCENARIOS}/satellite_two_arrays.yaml")
    model = scene.model
    assert model.joint_types == ["free", "revolute", "revolute"]
    assert model.parents == [-1, 0, 0] and model.body_names == ["bus", "left_array", "right_array"]
    assert_close(model.neutral(), [0, 0, 0, 1, 0, 0, 0, 0, 0], 0)
    q = model.normalize([1, 2, 3, 2, 0, 0, 0, 0.5, 0.25])
    assert_close(q[3:7], [1, 0, 0, 0], 1e-15)
    # a quarter turn about z in one step, and the reverse map back to v
    v = np.array([0, 0, np.pi / 2, 1, 0, 0, 0, 0])
    q1 = model.integrate(model.neutral(), v, 1.0)
    assert_close(q1[:7], [1, 0, 0, np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], 1e-15)
    assert_close(model.velocity(q, model.qdot(q, v)), v, 1e-14)
    assert_close(scene.q0, [0, 0, 0, 1, 0, 0, 0, 0.3, -0.2], 0)
    scene.q0 = [0, 0, 0, 1 + 4e-7, 0, 0, 0, 0, 0]  # within 1e-6 of unit norm: normalized when set
    assert_close(scene.q0[3], 1.0, 0)
    with pytest.raises(soadyn.Error, match="Scenario.q0: joint 'bus': expected a unit quaternion .* got norm 2$"):
        scene.q0 = [0, 0, 0, 2, 0, 0, 0, 0, 0]  # far from it: refused (test_no_silent_results.py)
    scene.settings.t_end = 3.5
    assert scene.settings.t_end == 3.5


# ---- memory: which results share memory with Data ---------------------------------------------

def test_results_are_read_only_views_of_data(rng):
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    q, v, tau = random_state(rng, model)
    views = {"M": soadyn.mass_matrix(model, data, q), "bias": soadyn.bias_forces(model, data, q, v),
             "tau": soadyn.inverse_dynamics(model, data, q, v, tau),
             "qdd": soadyn.forward_dynamics(model, data, q, v, tau)}
    for name, x in views.items():
        assert np.shares_memory(x, getattr(data, name)), name
        assert not x.flags.writeable, name
        with pytest.raises(ValueError):
            x[0] = 1.0
    # the next call overwrites the view: the same memory, the new state's values
    M1 = soadyn.mass_matrix(model, data, q)
    keep = M1.copy()
    q2 = q + 0.5
    M2 = soadyn.mass_matrix(model, data, q2)
    assert np.shares_memory(M1, M2) and np.array_equal(M1, M2)
    assert not np.allclose(keep, M2)
    # fresh arrays where Data holds no result
    J1, J2 = soadyn.jacobian(model, data, q), soadyn.jacobian(model, data, q)
    L1 = soadyn.mass_matrix_literal(model, data, q)
    assert not np.shares_memory(J1, J2) and J1.flags.writeable and L1.flags.writeable
    for x in (J1, L1, *soadyn.momentum(model, data, q, v)):
        for name in ("M", "bias", "tau", "qdd", "R", "eta", "G", "V"):
            assert not np.shares_memory(x, getattr(data, name))
    assert np.shares_memory(data.R, data.R) and data.R.shape == (3, 3, 3) and data.G.shape == (6, 3)


def test_derivatives_are_read_only_views_of_data(rng):
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    q, v, tau = random_state(rng, model)
    fd = soadyn.forward_dynamics_derivatives(model, data, q, v, tau)
    kept = [x.copy() for x in fd]
    idd = soadyn.inverse_dynamics_derivatives(model, data, q, v, tau)
    views = dict(zip(("dqdd_dq", "dqdd_dv", "dqdd_dtau", "dtau_dq", "dtau_dv"), (*fd, *idd)))
    for name, x in views.items():
        assert np.shares_memory(x, getattr(data, name)) and x.shape == (model.nv, model.nv), name
        assert not x.flags.writeable, name
        with pytest.raises(ValueError):
            x[0, 0] = 1.0
    # inverse_dynamics_derivatives leaves forward_dynamics_derivatives' results alone; minverse
    # returns its own 𝓜⁻¹ (data.Minv), the same numbers, and leaves data.dqdd_dtau alone
    for x, k in zip(fd, kept):
        assert np.array_equal(x, k)
    Minv = soadyn.minverse(model, data, q)
    assert Minv is data.Minv and not np.shares_memory(Minv, fd[2])
    assert_close(Minv, kept[2], 1e-12)
    soadyn.minverse(model, data, q + 0.3)
    assert np.array_equal(fd[2], kept[2])
    # the next call overwrites them; a view outlives its Data
    q2 = q + 0.5
    again = soadyn.forward_dynamics_derivatives(model, data, q2, v, tau)
    assert all(a is b for a, b in zip(again, fd)) and not np.allclose(fd[0], kept[0])
    expected = [x.copy() for x in again]
    del data, again
    gc.collect()
    for d in [model.create_data() for _ in range(20)]:
        soadyn.forward_dynamics_derivatives(model, d, q, v, tau)
    assert all(np.array_equal(x, e) for x, e in zip(fd, expected))


def test_a_view_keeps_the_memory_alive(rng):
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    q, v, tau = random_state(rng, model)
    M = soadyn.mass_matrix(model, data, q)
    R = data.R
    expected_M, expected_R = M.copy(), R.copy()
    del data
    gc.collect()
    # the memory would be reused by these if the Data had been freed
    others = [model.create_data() for _ in range(50)]
    for d in others:
        soadyn.mass_matrix(model, d, q + 1.0)
    assert np.array_equal(M, expected_M) and np.array_equal(R, expected_R)


def test_inputs_of_any_layout(rng):
    model = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    q, v, tau = random_state(rng, model)
    ref = soadyn.forward_dynamics(model, data, q, v, tau).copy()
    big = np.zeros((3, 4), order="F")
    big[:, 1] = q                 # a column of a Fortran array: contiguous
    strided = np.zeros(9)
    strided[::3] = v              # every third entry: a strided view, read in place
    rows = np.zeros((3, 3))
    rows[:, 2] = tau              # a column of a C array: stride 24 bytes
    assert_close(soadyn.forward_dynamics(model, data, big[:, 1], strided[::3], rows[:, 2]), ref, 0)
    tau32 = tau.astype(np.float32)  # converted once to float64
    ref32 = soadyn.forward_dynamics(model, data, q, v, tau32.astype(np.float64)).copy()
    assert_close(soadyn.forward_dynamics(model, data, list(q), tuple(v), tau32), ref32, 0)
    assert_close(soadyn.forward_dynamics(model, data, q[::-1][::-1], v, tau), ref, 0)
    assert_close(soadyn.forward_dynamics(model, data, q.astype(">f8"), v, tau), ref, 0)  # big-endian: converted
    backwards = q[::-1].copy()
    assert_close(soadyn.forward_dynamics(model, data, backwards[::-1], v, tau), ref, 0)  # negative stride
    ints = soadyn.mass_matrix(model, data, [0, 1, 0]).copy()  # ints converted
    assert_close(ints, soadyn.mass_matrix(model, data, np.array([0.0, 1.0, 0.0])), 0)


# ---- stubs, docstrings and help ---------------------------------------------------------------

def _runtime_params(obj):
    """parameter names from a pybind11 signature line, or from the Python function"""
    doc = obj.__doc__ or ""
    m = re.match(r"\w+\((.*?)\)\s*->", doc)
    if m:
        names = [p.split(":")[0].strip() for p in re.split(r",\s*(?![^\[]*\])", m.group(1)) if p.strip()]
        return [n for n in names if n not in ("self", "*")]
    import inspect
    return [p for p in inspect.signature(obj).parameters if p != "self"]


def test_stub_names_every_public_object_with_its_parameters():
    stub = ast.parse(open(os.path.join(os.path.dirname(soadyn.__file__), "__init__.pyi")).read())
    functions = {n.name: n for n in stub.body if isinstance(n, ast.FunctionDef)}
    classes = {n.name: n for n in stub.body if isinstance(n, ast.ClassDef)}
    constants = {n.target.id for n in stub.body if isinstance(n, ast.AnnAssign)}
    assert {"JOINT_TYPES", "METHODS", "DYNAMICS", "__version__"} <= constants
    public = set(soadyn.__all__) - constants
    assert public == set(functions) | set(classes)
    for name, node in functions.items():
        stub_params = [a.arg for a in node.args.args + node.args.kwonlyargs]
        assert stub_params == _runtime_params(getattr(soadyn, name)), name
    for cname, node in classes.items():
        cls = getattr(soadyn, cname)
        for item in node.body:
            if isinstance(item, ast.FunctionDef) and not item.name.startswith("__"):
                assert hasattr(cls, item.name), f"{cname}.{item.name}"
                if not any(isinstance(d, ast.Name) and d.id == "property" for d in item.decorator_list):
                    stub_params = [a.arg for a in item.args.args[1:]]
                    assert stub_params == _runtime_params(getattr(cls, item.name)), f"{cname}.{item.name}"
            elif isinstance(item, ast.AnnAssign):
                field = item.target.id
                dataclass_fields = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set()
                assert hasattr(cls, field) or field in dataclass_fields, f"{cname}.{field}"


def test_docstrings_give_equations_and_shapes():
    for name in ("mass_matrix", "bias_forces", "inverse_dynamics", "forward_dynamics", "jacobian", "mass_matrix_literal"):
        doc = getattr(soadyn, name).__doc__
        assert "(nv" in doc or "(6N" in doc, name
        assert any(s in doc for s in ("=", "eq.")), name
    text = pydoc.render_doc(soadyn, renderer=pydoc.plaintext)
    for needle in ("eq. 14", "Model/Data", "read-only views", "simulate(", "read_log(", "soadyn.Error"):
        assert needle in text, needle


def test_inputs_of_a_scenario():
    """the stiff arm's springs and damper: τ = −k (q − rest) − c q̇, V = ½ k (q − rest)²"""
    text = open(f"{SCENARIOS}/stiff_arm.yaml").read().replace("inputs:\n", """inputs:
  torques:
    - {joint: theta1, constant: 0.5, amplitude: 2.0, frequency: 3.0, phase: 0.25}
""")
    scene = soadyn.parse_scenario(text, f"{SCENARIOS}/stiff_arm_driven.yaml")
    inputs = scene.inputs
    assert len(inputs) == 4
    assert [s["joint"] for s in inputs.springs] == ["theta2", "theta3"] and inputs.dampers[0]["damping"] == 2.0e3
    assert inputs.torques[0]["dof"] == 0
    q, v, t = np.array([0.1, -0.2, 0.3]), np.array([1.0, 2.0, -3.0]), 0.7
    tau = [0.5 + 2.0 * np.sin(2 * np.pi * 3.0 * t + 0.25), -20.0 * -0.2, -2.0e4 * 0.3 - 2.0e3 * -3.0]
    assert_close(inputs.evaluate(t, q, v), tau, 1e-15)
    assert_close(inputs.spring_energy(q), 0.5 * 20.0 * 0.04 + 0.5 * 2.0e4 * 0.09, 1e-15)


def test_joint_types_and_a_ball_joint(rng):
    """the library's registries by name; the spherical pendulum's 𝓜 = I_pivot in the bob's frame"""
    assert soadyn.JOINT_TYPES == ("revolute", "prismatic", "ball", "planar", "free", "helical", "fixed")
    assert {"cvode-adams", "cvode-bdf", "rk4", "euler", "symplectic-euler", "implicit-midpoint"} <= set(soadyn.METHODS)
    assert soadyn.DYNAMICS == ("dense", "sparse", "aba")
    model = soadyn.load(f"{SCENARIOS}/spherical_pendulum.yaml")
    assert model.joint_types == ["ball"] and (model.nq, model.nv) == (4, 3)
    assert model.q_names == ["pivot.qw", "pivot.qx", "pivot.qy", "pivot.qz"]
    assert model.v_names == ["pivot.wx", "pivot.wy", "pivot.wz"]
    data = model.create_data()
    for _ in range(5):
        q = model.normalize(rng.normal(size=4))
        # ω in the child's frame: 𝓜 is the inertia about the pivot in body axes, whatever q
        assert_close(soadyn.mass_matrix(model, data, q), np.diag([1.001, 1.001, 0.001]), 1e-14)
    traj = soadyn.simulate(f"{SCENARIOS}/spherical_pendulum.yaml", t_end=2.0)
    assert traj.summary.completed and np.abs(traj.energy_error).max() < 1e-7
    assert_close(np.linalg.norm(traj.q, axis=1), np.ones(len(traj)), 1e-9)
    assert_close(traj.angular_momentum[:, 2], np.full(len(traj), traj.angular_momentum[0, 2]), 1e-8)


def test_a_helical_joint(rng):
    """screw_lift's nut: 𝓜 = I_zz + m_nut pitch² + the hanging arm's share, the nut rising pitch · θ"""
    model = soadyn.load(f"{SCENARIOS}/screw_lift.yaml")
    assert model.joint_types == ["helical", "revolute"] and (model.nq, model.nv) == (2, 2)
    assert_close(model.pitches, [0.05, 0.0], 0)
    data = model.create_data()
    q = np.array([rng.uniform(-3, 3), 0.0])
    # arm hanging straight down at x = 0.1 (its cm at (0.1, 0, −0.3) in the nut's frame, Ixx about its cm)
    nut = 0.02 + 2.0 * 0.05 ** 2
    arm = 0.0002 + 0.5 * (0.1 ** 2 + 0.05 ** 2)
    assert_close(soadyn.mass_matrix(model, data, q)[0, 0], nut + arm, 1e-12)
    traj = soadyn.simulate(f"{SCENARIOS}/screw_lift.yaml", t_end=2.0)
    assert traj.summary.completed and np.abs(traj.energy_error).max() < 1e-6


def test_version_is_the_libraries():
    from conftest import cli
    assert re.fullmatch(r"\d+\.\d+\.\d+", soadyn.__version__)
    assert soadyn.__version__ in cli("--version").stdout


def test_derivatives_against_differences_and_each_other(rng):
    """id_derivatives and fd_derivatives along the tangent (Model.integrate with h = 1) against
    central differences, and ∂q̈/∂x = −𝓜⁻¹ ∂τ/∂x at q̈"""
    model = soadyn.load(f"{SCENARIOS}/satellite_two_arrays.yaml")
    data = model.create_data()
    q, v, tau = random_state(rng, model)
    dqdd_dq, dqdd_dv, Minv = soadyn.forward_dynamics_derivatives(model, data, q, v, tau)
    qdd = soadyn.forward_dynamics(model, data, q, v, tau).copy()
    dtau_dq, dtau_dv = soadyn.inverse_dynamics_derivatives(model, data, q, v, qdd)
    assert_close(Minv, np.linalg.inv(soadyn.mass_matrix(model, data, q)), 1e-10)
    assert_close(dqdd_dq, -Minv @ dtau_dq, 1e-9)
    assert_close(dqdd_dv, -Minv @ dtau_dv, 1e-9)
    h = 1e-6
    for c in range(model.nv):
        e = np.zeros(model.nv)
        e[c] = h
        fp = soadyn.forward_dynamics(model, data, model.integrate(q, e, 1.0), v, tau).copy()
        fm = soadyn.forward_dynamics(model, data, model.integrate(q, -e, 1.0), v, tau).copy()
        assert_close(dqdd_dq[:, c], (fp - fm) / (2 * h), 1e-6)
        tp = soadyn.inverse_dynamics(model, data, q, v + e, qdd).copy()
        tm = soadyn.inverse_dynamics(model, data, q, v - e, qdd).copy()
        assert_close(dtau_dv[:, c], (tp - tm) / (2 * h), 1e-6)
