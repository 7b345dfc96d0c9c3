"""Every kind of bad input raises soadyn.Error (a ValueError) with the command line's message."""
import os

import numpy as np
import pytest

import soadyn
from conftest import SCENARIOS, cli, cli_error


def raised(fn, *args, **kwargs):
    with pytest.raises(soadyn.Error) as e:
        fn(*args, **kwargs)
    assert isinstance(e.value, ValueError)
    return str(e.value)


def test_error_is_a_value_error():
    assert issubclass(soadyn.Error, ValueError)


BAD_BODY = "bodies:\n  - name: a\n    joint: {type: revolute, axis: [0, 0, 1]}\n    mass: -1\n"
BAD_URDF = """<?xml version="1.0"?>
<robot name="pend">
  <link name="world"/>
  <link name="bob">
    <inertial><origin xyz="0 0 -1"/><mass value="2"/>
      <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="hinge" type="continuous">
    <parent link="world"/><child link="bob"/><axis xyz="1 0 0"/>
  </joint>
</robot>"""


def test_files_give_the_command_lines_messages(tmp_path):
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD_BODY)
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"\x00\x01binary")
    unknown = tmp_path / "unknown.yaml"
    unknown.write_text("bodies:\n  - name: a\n    joint: {type: helical, axis: [0, 0, 1]}\n    mass: 1\n")
    urdf = tmp_path / "pend.urdf"
    urdf.write_text(BAD_URDF)
    cases = [("/nonexistent.yaml", {}, "cannot open the file"), (str(empty), {}, "the file is empty"),
             (str(bad), {}, "bad.yaml:4:11: body 'a'.mass: expected a positive mass"),
             (str(tmp_path), {}, "is a directory"), (str(binary), {}, "a binary file, expected text"),
             (str(unknown), {}, "unknown.yaml:3"),
             (str(urdf), {"free_root": True}, "pend.urdf:3: link 'world': inertial: expected mass properties"),
             (f"{SCENARIOS}/double_pendulum.yaml", {"free_root": True}, "--free-root applies to URDF models")]
    for path, kw, expect in cases:
        args = ["inspect", path] + (["--free-root"] if kw.get("free_root") else [])
        message = cli_error(*args)
        for fn in (soadyn.load, soadyn.load_scenario):
            got = raised(fn, path, **kw)
            assert got == message, (got, message)
            assert expect in got, got


def test_parse_scenario_names_the_given_path():
    msg = raised(soadyn.parse_scenario, BAD_BODY, "inline.yaml")
    assert msg.startswith("inline.yaml:4:11: body 'a'.mass: expected a positive mass"), msg


def test_vector_sizes_shapes_and_models():
    model = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    other = soadyn.load(f"{SCENARIOS}/three_link_arm.yaml")
    data = model.create_data()
    assert raised(soadyn.mass_matrix, model, data, [1.0, 2.0, 3.0]) == "mass_matrix: q: expected 2 entries, got 3"
    assert raised(soadyn.bias_forces, model, data, [0, 0], [1.0]) == "bias_forces: v: expected 2 entries, got 1"
    assert raised(soadyn.inverse_dynamics, model, data, [0, 0], [0, 0], [1]) == \
        "inverse_dynamics: qdd: expected 2 entries, got 1"
    assert raised(soadyn.forward_dynamics, model, data, [0, 0], [0, 0], np.zeros(5)) == \
        "forward_dynamics: tau: expected 2 entries, got 5"
    assert raised(soadyn.mass_matrix, model, data, np.zeros((2, 1))) == \
        "mass_matrix: q: expected a 1-D array of 2 entries, got shape (2, 1)"
    assert "this Data was built for another model" in raised(soadyn.mass_matrix, other, data, [0, 0, 0])
    assert raised(model.integrate, [0, 0], [0, 0, 0], 0.1) == \
        "Model.integrate: v: expected a 1-D array of 2 entries, got 3 entries"
    with pytest.raises(TypeError):  # not numbers at all: numpy's conversion refuses
        soadyn.mass_matrix(model, data, ["a", "b"])


def test_methods_and_settings(tmp_path):
    model = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    data = model.create_data()
    msg = raised(soadyn.forward_dynamics, model, data, [0, 0], [0, 0], [0, 0], method="fast")
    assert "fast" in msg and "dense" in msg, msg
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    assert raised(soadyn.simulate, scene, rtol=-1.0) == "simulation settings: rtol must lie in (0, 1), got -1"
    # the library's warnings, as the command line prints them, become RuntimeWarnings
    p = cli("run", f"{SCENARIOS}/double_pendulum.yaml", "--rtol", "1e-17", "--t-end", "0.01", "-q", "-o",
            tmp_path / "tiny_rtol.h5")
    assert p.returncode == 0, p.stderr
    cli_warning = p.stderr.strip().removeprefix("soadyn: warning: ")
    assert "rtol 1e-17 is below what double precision can deliver" in cli_warning, p.stderr
    with pytest.warns(RuntimeWarning) as w:
        soadyn.simulate(scene, rtol=1e-17, t_end=0.01)
    assert [str(x.message) for x in w] == [cli_warning]
    # a word is refused where it comes in, as the scenario reader and soadyn sweep refuse it
    msg = raised(soadyn.simulate, scene, method="rk5")
    assert msg == "method: unknown method 'rk5'; did you mean 'rk4'?", msg


def test_nothing_written_for_a_refused_run(tmp_path):
    scene = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml")
    out = tmp_path / "never.h5"
    for kw in ({"t_end": -1.0}, {"method": "rk5"}, {"dynamics": "fast"}):
        with pytest.raises(soadyn.Error):
            soadyn.simulate(scene, output=str(out), **kw)
        assert not out.exists(), kw
    welded = soadyn.parse_scenario("bodies:\n  - name: a\n    joint: {type: fixed}\n    mass: 1\n    inertia: [1, 1, 1]\n", "welded.yaml")
    assert "no degrees of freedom" in raised(soadyn.simulate, welded, output=str(out))
    assert not out.exists()
    msg = raised(soadyn.simulate, scene, t_end=0.1, output=str(tmp_path))
    assert msg == cli_error("run", f"{SCENARIOS}/double_pendulum.yaml", "-o", tmp_path), msg
    notes = tmp_path / "notes.txt"  # not a soadyn run file: refused, left as it was
    notes.write_text("keep me")
    msg = raised(soadyn.simulate, scene, t_end=0.1, output=str(notes))
    assert msg == cli_error("run", f"{SCENARIOS}/double_pendulum.yaml", "-o", notes), msg
    assert "not a soadyn run file" in msg and notes.read_text() == "keep me"


def test_read_log_refuses_what_is_not_a_run(tmp_path):
    assert "cannot read the run file" in raised(soadyn.read_log, str(tmp_path / "missing.h5"))
    text = tmp_path / "text.h5"
    text.write_text("hello")
    assert "cannot read the run file" in raised(soadyn.read_log, str(text))
    import h5py
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = np.zeros(3)
    assert "not a soadyn run file" in raised(soadyn.read_log, str(tmp_path / "other.h5"))


def test_arguments_by_position_and_name():
    """the algorithms parse their own arguments: the usual Python rules and TypeErrors"""
    model = soadyn.load(f"{SCENARIOS}/double_pendulum.yaml")
    data = model.create_data()
    ref = soadyn.forward_dynamics(model, data, [0.1, 0.2], [0.3, 0.4], [1, 2], "dense").copy()
    got = soadyn.forward_dynamics(tau=[1, 2], method="dense", v=[0.3, 0.4], q=[0.1, 0.2], data=data, model=model)
    assert np.array_equal(got, ref)
    for call, message in [
            (lambda: soadyn.mass_matrix(model), "mass_matrix() missing required argument 'data'"),
            (lambda: soadyn.mass_matrix(model, data, [0, 0], True, 1), "mass_matrix() takes 4 arguments (5 given)"),
            (lambda: soadyn.mass_matrix(model, data, [0, 0], [0, 0]), "kinematics: expected True or False, got list"),
            (lambda: soadyn.mass_matrix(model, data, q=[0, 0], x=1), "unexpected keyword argument 'x'"),
            (lambda: soadyn.mass_matrix(model, data, [0, 0], q=[1, 1]), "multiple values for argument 'q'"),
            (lambda: soadyn.mass_matrix(data, model, [0, 0]), "mass_matrix: model: expected a soadyn.Model, got Data"),
            (lambda: soadyn.bias_forces(model, None, [0, 0], [0, 0]), "bias_forces: data: expected a soadyn.Data, got NoneType"),
            (lambda: soadyn.forward_dynamics(model, data, [0, 0], [0, 0], [0, 0], 3), "method: expected a string")]:
        with pytest.raises(TypeError) as e:
            call()
        assert message in str(e.value), str(e.value)
    import inspect
    assert str(inspect.signature(soadyn.forward_dynamics)) == "(model, data, q, v, tau, method='aba')"
    assert str(inspect.signature(soadyn.mass_matrix)) == "(model, data, q, kinematics=True)"
    assert str(inspect.signature(soadyn.bias_forces)) == "(model, data, q, v, kinematics=True)"


def test_unknown_names_raise_key_error_with_the_nearest_name():
    model = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml").model
    assert model.joint_index("theta2") == 1 and model.body_index("upper") == 0
    with pytest.raises(KeyError) as e:
        model.joint_index("theta3")
    assert "no joint named 'theta3'; did you mean 'theta1'?" in str(e.value)
    with pytest.raises(KeyError) as e:
        model.body_index("tool0")
    assert "no body named 'tool0' (expected one of: upper, lower)" in str(e.value)


def test_non_finite_arguments_are_refused_naming_the_entry():
    model = soadyn.load_scenario(f"{SCENARIOS}/double_pendulum.yaml").model
    data = soadyn.Data(model)
    for bad in (np.nan, np.inf, -np.inf):
        q = np.array([0.1, bad])
        msg = raised(soadyn.mass_matrix, model, data, q)
        assert "q[1] = " in msg and "expected a finite number" in msg, msg
        msg = raised(soadyn.mass_matrix, model, data, [0.1, bad])  # a list takes the converting path
        assert "q[1] = " in msg, msg
        msg = raised(soadyn.mass_matrix, model, data, np.array([0.1, 0.0, bad, 0.0])[::2])  # read through its stride
        assert "q[1] = " in msg, msg
        msg = raised(soadyn.forward_dynamics, model, data, np.zeros(2), np.zeros(2), np.array([bad, 0.0]))
        assert "tau[0] = " in msg, msg
    assert np.isfinite(soadyn.mass_matrix(model, data, np.array([0.1, 0.2]))).all()


def test_inertias_breaking_the_triangle_inequality_warn_balance_or_refuse():
    urdf = os.path.join(os.path.dirname(SCENARIOS), "tests", "data", "urdf", "rounded_inertias.urdf")
    with pytest.warns(UserWarning, match=r"loaded as given 2 inertias .*'ankle_motor'.*'camera'"):
        model = soadyn.load(urdf)
    assert len(model.warnings) == 1
    with pytest.warns(UserWarning, match="balanced 2 inertias"):
        balanced = soadyn.load(urdf, inertia_check="balance")
    moments = np.linalg.eigvalsh(balanced.inertias[1])
    assert moments[2] <= (moments[0] + moments[1]) * (1 + 1e-12)
    assert "'camera' [0.002 0.003 0.00512]" in raised(soadyn.load, urdf, inertia_check="strict")
    with pytest.raises(ValueError, match="did you mean 'strict'"):
        soadyn.load(urdf, inertia_check="strikt")
