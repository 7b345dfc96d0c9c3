"""MJCF files load in Python and through scenarios as they do in C++ (tests/io/test_mjcf.cpp checks the
dynamics against MuJoCo itself): the ignored features as a UserWarning, sites and welded bodies as
frames, the drawn pose as the initial state, a scenario's `urdf:` naming an MJCF file."""
import os

import numpy as np
import pytest

import soadyn
from conftest import ROOT

MJCF = os.path.join(ROOT, "tests", "data", "mjcf")


def test_load_lists_what_it_ignores_and_keeps_sites_as_frames():
    with pytest.warns(UserWarning, match=r"ignored: .*1 contact pair.*1 actuator"):
        model = soadyn.load(os.path.join(MJCF, "arm.xml"))
    assert model.nv == 6 and model.joint_names[:3] == ["yaw", "shoulder", "shoulder_roll"]
    assert {"tool", "lens", "camera"} <= set(model.frame_names)
    data = model.create_data()
    R, p = soadyn.frame_placement(model, data, model.neutral(), "tool")
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.all(np.isfinite(p))


def test_a_scenario_runs_an_mjcf_robot_from_its_drawn_pose(tmp_path):
    scene_file = tmp_path / "scene.yaml"
    scene_file.write_text(f"urdf: {os.path.join(MJCF, 'floating.xml')}\nsimulation: {{t_end: 0.2}}\n")
    with pytest.warns(UserWarning, match="armature"):
        scene = soadyn.load_scenario(str(scene_file))
    assert np.allclose(scene.q0[:3], [0.1, -0.2, 1.0])  # the free joint where the file draws it
    traj = soadyn.simulate(scene)
    # a free fall under gravity: the centre of mass drops g t²/2 whatever the limbs do
    m = soadyn.load(os.path.join(MJCF, "floating.xml"))
    data = m.create_data()
    z0, z1 = soadyn.com(m, data, traj.q[0])[2], soadyn.com(m, data, traj.q[-1])[2]
    assert abs((z0 - z1) - 0.5 * 9.81 * traj.t[-1] ** 2) < 1e-6


def test_compiler_errors_are_soadyn_errors_with_the_line():
    with pytest.raises(soadyn.Error, match=r"bad_joint.xml:4: joint: .*'bogus'"):
        soadyn.load(os.path.join(MJCF, "bad_joint.xml"))


def test_a_free_flying_mjcf_body_conserves_energy_under_cvode():
    """floating.xml tumbling without gravity (torso, ball-jointed head, hinged legs): nothing does work,
    so the energy stays E(0) to the integrator's tolerance, and so do both momenta"""
    with pytest.warns(UserWarning):
        scene = soadyn.load_scenario(os.path.join(MJCF, "floating.xml"), gravity=[0, 0, 0])
    v0 = np.zeros(scene.model.nv)
    v0[:6] = [1.5, -0.7, 2.0, 0.3, 0.1, -0.2]   # the torso spun and thrown
    v0[6:9] = [3.0, 0.0, -2.0]                   # the head spun on its ball joint
    v0[9:] = [4.0, -3.0, 2.5]                    # the legs swinging
    scene.v0 = v0
    traj = soadyn.simulate(scene, "cvode-bdf", rtol=1e-10, atol=1e-12, t_end=3.0)
    assert traj.summary.status == "completed", traj.summary.status
    e = traj.total_energy
    assert e[0] > 1.0
    assert np.abs(e - e[0]).max() < 1e-7 * e[0]
    for h in (traj.linear_momentum, traj.angular_momentum):
        assert np.abs(h - h[0]).max() < 1e-7 * (1 + np.abs(h[0]).max())


def test_view_draws_the_geoms(tmp_path):
    """soadyn run then view of an MJCF model: the torso's box geom (half-sizes 0.15 0.1 0.25) drawn
    with its full edges, the legs' capsules as cylinders"""
    import subprocess
    exe = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
    run = subprocess.run([exe, "run", os.path.join(MJCF, "floating.xml"), "--t-end", "0.1", "-q", "-o",
                          str(tmp_path / "f.h5")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    view = subprocess.run([exe, "view", str(tmp_path / "f.h5"), "-o", str(tmp_path / "f.html"), "-q"],
                          capture_output=True, text=True, timeout=120)
    assert view.returncode == 0, view.stderr
    page = (tmp_path / "f.html").read_text()
    assert '"kind":"box","size":[0.3,0.2,0.5]' in page
    assert page.count('"kind":"cylinder"') >= 3


def test_an_mjcf_connect_is_a_loop_that_runs_logs_and_pickles(tmp_path):
    """tests/data/mjcf/four_bar_connect.xml, a four-bar closed by <equality connect>, loaded alone: its
    connect is a point loop, held closed, its forces logged; a pickled scene (a Dask worker's) gets the
    loop back from the files the scene handed MuJoCo"""
    import pickle
    with pytest.warns(UserWarning, match=r"softness of 1 equality constraint \(held exactly as a loop\)"):
        sc = soadyn.load_scenario(os.path.join(MJCF, "four_bar_connect.xml"))
    out = str(tmp_path / "four_bar.h5")
    traj = soadyn.simulate(sc, t_end=1.0, output=out)
    assert traj.summary.completed, traj.summary.status
    assert traj.loop_rows == ["closing.x", "closing.y", "closing.z"]
    assert traj.loop_closure.max() < 1e-10
    assert abs(traj.loop_forces[:, :2]).max() > 1.0  # gravity pulls the coupler on the rocker
    assert abs(traj.q[:, 0] - traj.q[0, 0]).max() > 0.1  # it swings
    back = pickle.loads(pickle.dumps(sc))
    again = soadyn.simulate(back, t_end=1.0)
    np.testing.assert_array_equal(again.q, traj.q)
    np.testing.assert_array_equal(again.loop_forces, traj.loop_forces)
