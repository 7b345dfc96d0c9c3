"""Frames and task space from Python: the C++ names, frames of a URDF's fixed joints and a scenario's
frames:, Jacobians against differences of the placement, A_G against momentum, Λ against numpy's
dense formula, the Coriolis matrix against bias, and the errors."""
import os

import numpy as np
import pytest

import soadyn
from conftest import ROOT, SCENARIOS, assert_close, cli, cli_error, random_tree_yaml

ARM = os.path.join(ROOT, "tests", "data", "frames", "arm_fixed.urdf")
H = 1e-5


def rotation_vector(R):
    """θ with R = exp(θ̃)"""
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    if angle < 1e-12:
        return np.zeros(3)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return angle * w / (2 * np.sin(angle))


def test_fixed_links_are_frames_and_names_are_checked():
    model = soadyn.load(ARM)
    assert model.nbodies == 3
    assert {"base_link", "link1", "link2", "link3", "flange", "tool", "camera"} <= set(model.frame_names)
    assert model.frame_bodies[model.frame_index("tool")] == model.body_index("link3")
    assert model.frame_bodies[model.frame_index("camera")] == -1  # welded to the world with base_link
    with pytest.raises(KeyError, match="did you mean 'tool'"):
        model.frame_index("tol")
    data = model.create_data()
    q = np.zeros(model.nq)
    with pytest.raises(KeyError, match="did you mean 'flange'"):
        soadyn.frame_jacobian(model, data, q, "flang")
    with pytest.raises(soadyn.Error, match="did you mean 'world'"):
        soadyn.frame_jacobian(model, data, q, "tool", reference="wrld")
    with pytest.raises(soadyn.Error, match="frame: expected an index"):
        soadyn.frame_jacobian(model, data, q, 99)
    with pytest.raises(soadyn.Error, match="q: expected 3 entries"):
        soadyn.frame_jacobian(model, data, np.zeros(2), "tool")
    # a frame by index is the frame by name
    assert_close(soadyn.frame_jacobian(model, data, q, model.frame_index("tool")),
                 soadyn.frame_jacobian(model, data, q, "tool"), 0)


def test_scenario_frames_and_add_frame():
    text = open(f"{SCENARIOS}/double_pendulum.yaml").read() + "frames:\n  tip: {body: lower, position: [0, 0, -1]}\n"
    model = soadyn.parse_scenario(text, f"{SCENARIOS}/dp_tip.yaml").model
    data = model.create_data()
    t1, t2 = 0.4, -1.1
    R, p = soadyn.frame_placement(model, data, [t1, t2], "tip")
    assert_close(p, [0, np.sin(t1) + np.sin(t1 + t2), -np.cos(t1) - np.cos(t1 + t2)], 1e-14)
    i = model.add_frame("above_tip", "tip", position=[0, 0, 0.5], rpy=[0, 0, np.pi / 2])
    assert model.frame_names[i] == "above_tip"
    R2, p2 = soadyn.frame_placement(model, data, [t1, t2], i)
    assert_close(p2, p + R @ [0, 0, 0.5], 1e-14)
    with pytest.raises(soadyn.Error, match="already has"):
        model.add_frame("tip", "lower")


@pytest.mark.parametrize("free_root", [False, True])
def test_jacobians_against_differences_of_the_placement(rng, free_root):
    model = soadyn.load(ARM, free_root=free_root)
    data = model.create_data()
    for _ in range(3):
        q = model.normalize(rng.normal(size=model.nq))
        v = rng.normal(size=model.nv)
        for frame in ("tool", "flange", "camera", "link2"):
            Ra, pa = soadyn.frame_placement(model, data, model.integrate(q, v, -H), frame)
            Rb, pb = soadyn.frame_placement(model, data, model.integrate(q, v, H), frame)
            R, p = soadyn.frame_placement(model, data, q, frame)
            w, pd = rotation_vector(Rb @ Ra.T) / (2 * H), (pb - pa) / (2 * H)
            expected = {"local_world_aligned": np.r_[w, pd], "local": np.r_[R.T @ w, R.T @ pd],
                        "world": np.r_[w, pd - np.cross(w, p)]}
            for reference, e in expected.items():
                J = soadyn.frame_jacobian(model, data, q, frame, reference)
                assert J.shape == (6, model.nv)
                assert_close(J @ v, e, 1e-7)
                assert_close(soadyn.frame_velocity(model, data, q, v, frame, reference), J @ v, 1e-12)
                # J̇ v against differences of J v
                Jdv = soadyn.frame_jacobian_dot_times_v(model, data, q, v, frame, reference)
                diff = (soadyn.frame_jacobian(model, data, model.integrate(q, v, H), frame, reference)
                        - soadyn.frame_jacobian(model, data, model.integrate(q, v, -H), frame, reference)) @ v / (2 * H)
                assert_close(Jdv, diff, 1e-7)
            # the point Jacobian of the tool's origin on its body
            if frame == "tool":
                body = model.frame_bodies[model.frame_index("tool")]
                Rb_, eta = soadyn.frame_placement(model, data, q, model.body_names[body])
                Jp = soadyn.point_jacobian(model, data, q, model.body_names[body], Rb_.T @ (p - eta))
                assert_close(Jp, soadyn.frame_jacobian(model, data, q, "tool")[3:], 1e-13)


def test_centroidal_momentum_and_com(rng):
    model = soadyn.parse_scenario(random_tree_yaml(rng, 7, free_root=True)).model
    data = model.create_data()
    q = model.normalize(rng.normal(size=model.nq))
    v = rng.normal(size=model.nv)
    c = soadyn.com(model, data, q)
    linear, angular = soadyn.momentum(model, data, q, v)
    AG = soadyn.centroidal_momentum_matrix(model, data, q)
    assert_close(AG @ v, np.r_[angular - np.cross(c, linear), linear], 1e-11)
    assert_close(soadyn.centroidal_momentum(model, data, q, v), AG @ v, 1e-11)
    Jc = soadyn.com_jacobian(model, data, q)
    assert_close(Jc @ v, soadyn.com_velocity(model, data, q, v), 1e-12)
    m, IG = soadyn.centroidal_inertia(model, data, q)
    assert m == pytest.approx(model.masses.sum(), rel=1e-12)
    assert_close(IG, IG.T, 1e-13)
    assert np.linalg.eigvalsh(IG).min() > 0
    dA = (soadyn.centroidal_momentum_matrix(model, data, model.integrate(q, v, H))
          - soadyn.centroidal_momentum_matrix(model, data, model.integrate(q, v, -H))) @ v / (2 * H)
    assert_close(soadyn.centroidal_momentum_matrix_dot_times_v(model, data, q, v), dA, 1e-7)


def test_operational_space_inertia_and_coriolis(rng):
    model = soadyn.load(os.path.join(ROOT, "tests", "data", "arm7.urdf"))
    model.add_frame("tcp", model.body_names[-1], position=[0.0, 0.0, 0.1])
    data = model.create_data()
    q = rng.uniform(-1, 1, model.nq)
    v = rng.normal(size=model.nv)
    J = soadyn.frame_jacobian(model, data, q, "tcp")
    M = soadyn.mass_matrix(model, data, q).copy()
    Lambda = soadyn.operational_space_inertia(model, data, q, J)
    assert_close(Lambda, np.linalg.inv(J @ np.linalg.solve(M, J.T)), 1e-8)
    C = soadyn.coriolis_matrix(model, data, q, v)
    gravity = soadyn.bias_forces(model, data, q, np.zeros(model.nv)).copy()
    assert_close(C @ v, soadyn.bias_forces(model, data, q, v) - gravity, 1e-11)
    # a 6-row task on two joints
    pend = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    d2 = pend.create_data()
    J2 = soadyn.frame_jacobian(pend, d2, [0.3, 0.4], "lower")
    with pytest.raises(soadyn.Error, match="singular: rank 2 of 6"):
        soadyn.operational_space_inertia(pend, d2, [0.3, 0.4], J2)
    with pytest.raises(soadyn.Error, match="J: expected k"):
        soadyn.operational_space_inertia(pend, d2, [0.3, 0.4], np.zeros((3, 5)))


def test_log_frames_puts_their_poses_in_the_run_file(tmp_path):
    h5py = pytest.importorskip("h5py")
    text = open(f"{SCENARIOS}/double_pendulum.yaml").read() + (
        "frames:\n  tip: {body: lower, position: [0, 0, -1], rpy: [0.2, 0, 0]}\nlog: {frames: [tip, upper]}\n")
    scene = soadyn.parse_scenario(text, f"{SCENARIOS}/dp_tip.yaml")
    out = tmp_path / "run.h5"
    soadyn.simulate(scene, "rk4", dt=1e-3, t_end=0.2, output_dt=0.05, output=str(out))
    with h5py.File(out, "r") as f:
        assert [n.decode() if isinstance(n, bytes) else n for n in f["frames/names"][:]] == ["tip", "upper"]
        pos, att, q = f["frames/position"][:], f["frames/orientation"][:], f["q"][:]
        assert pos.shape == (len(q), 2, 3) and att.shape == (len(q), 2, 4)
        assert f["frames/position"].attrs["units"] == b"m"  # fixed-length strings: bytes
        names = [n.decode() for n in f["samples"].attrs["column_names"]]
        assert "frames.position.tip.x" in names and "frames.orientation.upper.w" in names
    model, data = scene.model, scene.model.create_data()
    for k in range(len(q)):
        R, p = soadyn.frame_placement(model, data, q[k], "tip")
        assert_close(pos[k, 0], p, 1e-14)
        w = np.sqrt(1 + np.trace(R)) / 2  # the quaternion's w (w >= 0), then x from R
        assert_close(att[k, 0, 0], w, 1e-12)
        assert_close(att[k, 0, 1], (R[2, 1] - R[1, 2]) / (4 * w), 1e-12)
    # the names are checked where the scenario says them
    with pytest.raises(soadyn.Error, match=r"log.frames\[0\]: no frame named 'tpi'; did you mean 'tip'\?"):
        soadyn.parse_scenario(text.replace("[tip, upper]", "[tpi]"), f"{SCENARIOS}/dp_tip.yaml")


def test_read_log_gives_the_logged_frames(tmp_path):
    pytest.importorskip("h5py")
    # a top on a ball joint turns its frames every way; "top" is the body's own frame
    text = open(f"{SCENARIOS}/heavy_top.yaml").read() + (
        "frames:\n  rim: {body: top, position: [0.05, -0.02, 0.1], rpy: [0.3, -0.4, 1.1]}\nlog: {frames: [rim, top]}\n")
    scene = soadyn.parse_scenario(text, f"{SCENARIOS}/top_rim.yaml")
    out = tmp_path / "run.h5"
    soadyn.simulate(scene, "rk4", dt=1e-3, t_end=0.3, output_dt=0.02, output=str(out))
    traj = soadyn.read_log(str(out))
    assert list(traj.frames) == ["rim", "top"]
    model, data = scene.model, scene.model.create_data()
    T = len(traj)
    worst_p = worst_R = 0.0
    turned = []
    for name, poses in traj.frames.items():
        assert poses.position.shape == (T, 3) and poses.orientation.shape == (T, 4) and poses.rotation.shape == (T, 3, 3)
        for k in range(T):
            R, p = soadyn.frame_placement(model, data, traj.q[k], name)
            worst_p = max(worst_p, np.abs(poses.position[k] - p).max())
            worst_R = max(worst_R, np.abs(poses.rotation[k] - R).max())
        turned.append(np.abs(poses.rotation[-1] - poses.rotation[0]).max())
    assert worst_p < 1e-12 and worst_R < 1e-12, (worst_p, worst_R)
    assert min(turned) > 0.01  # the frames did move: the comparison is not of constants
    # a run that logged no frames has none
    plain = tmp_path / "plain.h5"
    soadyn.simulate(soadyn.load_scenario(f"{SCENARIOS}/heavy_top.yaml"), "rk4", dt=1e-3, t_end=0.05, output=str(plain))
    assert soadyn.read_log(str(plain)).frames == {}


def test_inspect_frame_prints_pose_and_jacobian():
    """`soadyn inspect --frame`: the same pose and Jacobian as the library's, in tables and in JSON"""
    import json
    q = [0.3, -0.5, 0.8]
    p = cli("inspect", ARM, "--q", ",".join(map(str, q)), "--frame", "tool", "--frame", "camera", "--json")
    assert p.returncode == 0, p.stderr
    frames = json.loads(p.stdout)["frames"]
    assert [f["name"] for f in frames] == ["tool", "camera"] and [f["body"] for f in frames] == ["link3", "world"]
    model = soadyn.load(ARM)
    data = model.create_data()
    R, pos = soadyn.frame_placement(model, data, q, "tool")
    assert_close(frames[0]["position"], pos, 1e-15)
    assert_close(frames[0]["jacobian"], soadyn.frame_jacobian(model, data, q, "tool"), 1e-15)
    w = np.sqrt(1 + np.trace(R)) / 2
    assert_close(frames[0]["orientation"][0], w, 1e-12)
    tables = cli("inspect", ARM, "--frame", "flange")
    assert tables.returncode == 0 and "frame      flange on link3: origin [" in tables.stdout, tables.stdout
    assert cli_error("inspect", ARM, "--frame", "tol") == "--frame: no frame named 'tol'; did you mean 'tool'?"


def test_part_gives_the_rows_of_the_spatial_quantity(rng):
    """Spatial quantities are [ω; v]: part="angular" is rows 0-2 of the 6-row result, part="linear"
    rows 3-5, for the four frame functions; a bad part names the choices.  The linear rows are the
    tool point's velocity by central differences of frame_placement (the angular rows are not)."""
    model = soadyn.load(os.path.join(ROOT, "tests", "data", "frames", "arm_fixed.urdf"))
    data = model.create_data()
    q, v, a = rng.uniform(-1, 1, model.nq), rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)
    calls = {
        "frame_jacobian": lambda part: soadyn.frame_jacobian(model, data, q, "tool", part=part),
        "frame_velocity": lambda part: soadyn.frame_velocity(model, data, q, v, "tool", part=part),
        "frame_acceleration": lambda part: soadyn.frame_acceleration(model, data, q, v, a, "tool", part=part),
        "frame_jacobian_dot_times_v": lambda part: soadyn.frame_jacobian_dot_times_v(model, data, q, v, "tool", part=part),
    }
    for name, f in calls.items():
        full = np.array(f("all"))
        assert full.shape[0] == 6, name
        assert np.array_equal(np.array(f("angular")), full[:3]), name
        assert np.array_equal(np.array(f("linear")), full[3:]), name
        with pytest.raises(ValueError, match=rf"{name}: part: expected 'all', 'angular' or 'linear', got 'lin'"):
            f("lin")
    h = 1e-6
    p = lambda x: soadyn.frame_placement(model, data, x, "tool")[1].copy()
    pdot = (p(q + h * v) - p(q - h * v)) / (2 * h)
    assert np.abs(soadyn.frame_velocity(model, data, q, v, "tool", part="linear") - pdot).max() < 1e-8
    assert np.abs(soadyn.frame_velocity(model, data, q, v, "tool", part="angular") - pdot).max() > 1e-3
