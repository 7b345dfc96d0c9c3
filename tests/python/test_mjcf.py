"""MJCF files load in Python and through scenarios as they do in C++ (tests/test_mjcf.cpp checks the
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
