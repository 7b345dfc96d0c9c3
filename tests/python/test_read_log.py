"""read_log gives back what the run returned, array for array: simulate(output=) runs (the
controlled arm hitting its limits: /control, /energy/impact_loss, /events; a scene with logged
frames and sensitivities; a Python controller) against read_log of their files, field by field.
Every dataset the file holds is enumerated with h5py and must be accounted for below: a dataset
the writer gains without read_log reading it back fails the test."""
import os
import struct

import h5py
import numpy as np
import pytest

import soadyn
from conftest import SCENARIOS

# each dataset a run file holds → how the Trajectory carries it (the test checks each of these)
TRAJECTORY_FIELDS = {
    "/time": "t", "/q": "q", "/qd": "v", "/qdd": "qdd",
    "/energy/kinetic": "kinetic_energy", "/energy/potential": "potential_energy", "/energy/total": "total_energy",
    "/energy/work_inputs": "work_inputs", "/energy/dissipated": "dissipated", "/energy/impact_loss": "impact_loss",
    "/momentum/linear": "linear_momentum", "/momentum/angular": "angular_momentum",
    "/bodies/position": "body_position", "/bodies/orientation": "body_orientation", "/bodies/com": "body_com",
    "/control": "control",
}
# the rest: where each is compared (the names of series and frames, the model's tree, the texts)
OTHER = {"/samples", "/events", "/scenario", "/robot", "/bodies/names", "/frames/names", "/frames/position",
         "/frames/orientation", "/sensitivities/initial_state", "/sensitivities/parameters", "/model/parents",
         "/model/joint_q_index", "/model/joint_v_index"}
SOLVER = {"status", "t_reached", "steps", "rhs_evals", "jac_evals", "error_test_failures", "nonlinear_iterations",
          "cpu_seconds", "quaternion_handling", "max_energy_balance_error", "final_energy_balance_error",
          "control_ticks", "stiffness_index", "stiffness_hint"}


def datasets(path):
    out = []
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.append("/" + name) if isinstance(obj, h5py.Dataset) else None)
    return out


def same_array(a, b, what):
    assert a is not None and b is not None, what
    assert np.shape(a) == np.shape(b), (what, np.shape(a), np.shape(b))
    assert np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True), what  # float64 round-trips to the bit


def compare(run, back, path, scene):
    names = datasets(path)
    unknown = [n for n in names if n not in TRAJECTORY_FIELDS and n not in OTHER and not n.startswith("/solver/")
               and not n.startswith("/model_files/")]
    assert unknown == [], f"datasets read_log does not account for: {unknown}"
    assert {n[len("/solver/"):] for n in names if n.startswith("/solver/")} <= SOLVER
    for field in Trajectory_arrays():
        same_array(getattr(run, field), getattr(back, field), field)
    for n in names:
        if n in TRAJECTORY_FIELDS:
            with h5py.File(path, "r") as f:
                same_array(f[n][()], getattr(back, TRAJECTORY_FIELDS[n]), n)
    # the summary: every field as the run returned it, the events and control ticks included
    assert back.summary == run.summary, (back.summary, run.summary)
    assert back.joint_names == run.joint_names and back.parents == run.parents and back.scenario == run.scenario
    with h5py.File(path, "r") as f:
        if "/bodies/names" in names:
            assert list(f["bodies/names"].asstr()[:]) == list(scene.model.body_names)
        if "/model/joint_v_index" in names:
            assert list(f["model/joint_v_index"][:]) == list(scene.model.idx_v)
        if "/model/joint_q_index" in names:
            assert list(f["model/joint_q_index"][:]) == list(scene.model.idx_q)
        if "/events" in names:
            assert len(f["events"]) == len(back.summary.events)
        if "/frames/names" in names:
            assert list(back.frames) == list(f["frames/names"].asstr()[:])
            for k, name in enumerate(back.frames):
                same_array(back.frames[name].position, f["frames/position"][:, k], name)
                same_array(back.frames[name].orientation, f["frames/orientation"][:, k], name)
    # /model_files/0 .. count-1: an MJCF model's files (name attribute, bytes), read back by the
    # library's reader as soadyn view takes them, the Scenario's model_files as the run stored them
    stored = [n for n in names if n.startswith("/model_files/")]
    read = soadyn._soadyn._read_run_file(path)["model_files"]
    with h5py.File(path, "r") as f:
        assert len(stored) == (int(f["model_files"].attrs["count"]) if stored else 0) == len(read)
        for k, (name, data) in enumerate(read):
            d = f[f"model_files/{k}"]
            assert d.dtype == np.uint8 and bytes(d[()]) == data
            assert d.attrs["name"].decode() == name
    if run.sensitivities is not None:
        for field in ("initial_state", "parameters", "state_names", "state_units", "parameter_names", "parameter_units"):
            a, b = getattr(run.sensitivities, field), getattr(back.sensitivities, field)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                same_array(a, b, field)
            else:
                assert list(a or []) == list(b or []), field


def Trajectory_arrays():
    return soadyn.Trajectory.ARRAYS + ("impact_loss", "control")


def test_the_controlled_arm_with_limits_reads_back_whole(tmp_path):
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "arm_control_limits.yaml"))
    out = str(tmp_path / "arm.h5")
    run = soadyn.simulate(scene, t_end=1.0, output=out)
    back = soadyn.read_log(out)
    assert len(run.summary.events) > 0 and np.abs(run.control).max() > 0 and run.impact_loss[-1] > 0
    assert run.summary.control_ticks > 0
    compare(run, back, out, scene)
    # the run's own books: its balance error, not one recomputed without the impacts' loss
    assert back.summary.max_energy_balance_error < 1e-6
    with h5py.File(out, "r") as f:
        assert back.summary.max_energy_balance_error == f["solver/max_energy_balance_error"][()]


def test_a_plain_run_reads_back_with_zero_control_and_impact_loss(tmp_path):
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    out = str(tmp_path / "p.h5")
    run = soadyn.simulate(scene, t_end=0.5, output=out)
    back = soadyn.read_log(out)
    assert not np.any(run.control) and not np.any(run.impact_loss)
    compare(run, back, out, scene)


def test_frames_sensitivities_and_a_python_controller_read_back_whole(tmp_path):
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    text = scene.text + "log: {frames: [upper, lower]}\n"
    scene = soadyn.parse_scenario(text, os.path.join(SCENARIOS, "double_pendulum.yaml"))
    out = str(tmp_path / "s.h5")
    run = soadyn.simulate(scene, t_end=0.2, output=out, sensitivities={"initial_state": True, "parameters": ["lower"]})
    back = soadyn.read_log(out)
    assert run.sensitivities is not None and run.sensitivities.parameters is not None
    compare(run, back, out, scene)
    assert set(back.frames) == {"upper", "lower"}
    out = str(tmp_path / "c.h5")
    run = soadyn.simulate(scene, t_end=0.2, output=out, controller=lambda t, q, v: -0.5 * np.asarray(v))
    assert np.abs(run.control).max() > 0
    compare(run, soadyn.read_log(out), out, scene)


@pytest.mark.parametrize("kind", ["dataset", "attribute"])
def test_variable_length_strings_in_a_layout_5_file_are_refused(tmp_path, kind):
    # a layout that writes none: refused before HDF5 follows them into the global heap
    scene = soadyn.load_scenario(os.path.join(SCENARIOS, "double_pendulum.yaml"))
    out = str(tmp_path / "p.h5")
    soadyn.simulate(scene, t_end=0.1, output=out)
    with h5py.File(out, "r+") as f:
        assert f.attrs["layout_version"] == 5
        if kind == "dataset":
            del f["scenario"]
            f["scenario"] = scene.text  # h5py: variable-length
        else:
            f["model"].attrs["q_names"] = ["theta1", "theta2"]
    with pytest.raises(soadyn.Error, match="variable-length strings, which this file's layout never writes"):
        soadyn.read_log(out)


def test_an_mjcf_model_s_files_are_stored_and_read_back(tmp_path):
    # a scenario whose model: is an MJCF file with an <include> and a mesh: every file MuJoCo was handed
    tris = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 0, 1), (1, 0, 0)),
            ((0, 0, 0), (0, 1, 0), (0, 0, 1)), ((1, 0, 0), (0, 0, 1), (0, 1, 0))]
    stl = b"\0" * 80 + struct.pack("<I", len(tris))
    for t in tris:
        stl += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *[0.1 * c for c in v]) for v in t) + b"\0\0"
    (tmp_path / "tet.stl").write_bytes(stl)
    body = ('<mujoco><body name="link" pos="0 0 1"><joint name="hinge" axis="0 1 0"/>'
            '<geom type="mesh" mesh="tet" contype="0" conaffinity="0"/></body></mujoco>\n')
    (tmp_path / "body.xml").write_text(body)
    (tmp_path / "robot.xml").write_text('<mujoco model="m"><asset><mesh name="tet" file="tet.stl"/></asset>'
                                        '<worldbody><include file="body.xml"/></worldbody></mujoco>\n')
    (tmp_path / "scene.yaml").write_text("model: robot.xml\n")
    scene = soadyn.load_scenario(str(tmp_path / "scene.yaml"))
    out = str(tmp_path / "mj.h5")
    run = soadyn.simulate(scene, t_end=0.1, output=out)
    back = soadyn.read_log(out)
    compare(run, back, out, scene)
    files = {os.path.basename(name): data for name, data in soadyn._soadyn._read_run_file(out)["model_files"]}
    assert files["body.xml"] == body.encode() and files["tet.stl"] == stl and len(files) == 3
