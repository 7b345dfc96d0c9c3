"""What each call overwrites (src/python/README.md, "What a call overwrites"): a result a call
returned, as a view into its Data, changes only when that same function is called again on that
Data.  Calls taking q (and v) set the Data's stage: its kinematics and velocity views (R, eta, V, …)
then hold that state, whichever call set it; those views are not any call's returned result.

Every (model, data, …) function of the stub is called at one state, what it returned kept as
returned and as a copy; then every function is called at another state; each earlier result must
still equal its copy unless its own function was called again."""
import ast
import functools
import os

import numpy as np
import pytest

import soadyn
from conftest import ROOT

FRAME_URDF = os.path.join(ROOT, "tests", "data", "frames", "arm_fixed.urdf")


def stub_functions():
    """names of the stub's functions whose first two parameters are (model, data)"""
    tree = ast.parse(open(os.path.join(ROOT, "src", "python", "soadyn", "__init__.pyi")).read())
    out = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            names = [a.arg for a in node.args.args[:2]]
            deprecated = any(isinstance(d, ast.Call) and getattr(d.func, "id", "") == "deprecated"
                             for d in node.decorator_list)
            if names == ["model", "data"] and not deprecated:
                out.append(node.name)
    return out


def calls(model, data, draw, J):
    """each (model, data, …) function with arguments at its own state (q, v, a) = draw(): two calls
    never share a state, so a call that fills another's result at its own state is caught too"""
    at = {
        "update_kinematics": lambda q, v, a: soadyn.update_kinematics(model, data, q),
        "update_velocities": lambda q, v, a: soadyn.update_velocities(model, data, q, v),
        "mass_matrix": lambda q, v, a: soadyn.mass_matrix(model, data, q),
        "mass_matrix_literal": lambda q, v, a: soadyn.mass_matrix_literal(model, data, q),
        "minverse": lambda q, v, a: soadyn.minverse(model, data, q),
        "bias_forces": lambda q, v, a: soadyn.bias_forces(model, data, q, v),
        "inverse_dynamics": lambda q, v, a: soadyn.inverse_dynamics(model, data, q, v, a),
        "forward_dynamics": lambda q, v, a: soadyn.forward_dynamics(model, data, q, v, a, method="dense"),
        "jacobian": lambda q, v, a: soadyn.jacobian(model, data, q),
        "inverse_dynamics_derivatives": lambda q, v, a: soadyn.inverse_dynamics_derivatives(model, data, q, v, a),
        "forward_dynamics_derivatives": lambda q, v, a: soadyn.forward_dynamics_derivatives(model, data, q, v, a),
        "kinetic_energy": lambda q, v, a: soadyn.kinetic_energy(model, data, q, v),
        "potential_energy": lambda q, v, a: soadyn.potential_energy(model, data, q),
        "momentum": lambda q, v, a: soadyn.momentum(model, data, q, v),
        "frame_placement": lambda q, v, a: soadyn.frame_placement(model, data, q, "tool"),
        "frame_velocity": lambda q, v, a: soadyn.frame_velocity(model, data, q, v, "tool"),
        "frame_acceleration": lambda q, v, a: soadyn.frame_acceleration(model, data, q, v, a, "tool"),
        "frame_jacobian": lambda q, v, a: soadyn.frame_jacobian(model, data, q, "tool"),
        "frame_jacobian_dot_times_v": lambda q, v, a: soadyn.frame_jacobian_dot_times_v(model, data, q, v, "tool"),
        "point_jacobian": lambda q, v, a: soadyn.point_jacobian(model, data, q, 1, [0.1, 0.0, 0.05]),
        "com": lambda q, v, a: soadyn.com(model, data, q),
        "com_velocity": lambda q, v, a: soadyn.com_velocity(model, data, q, v),
        "com_jacobian": lambda q, v, a: soadyn.com_jacobian(model, data, q),
        "centroidal_momentum_matrix": lambda q, v, a: soadyn.centroidal_momentum_matrix(model, data, q),
        "centroidal_momentum": lambda q, v, a: soadyn.centroidal_momentum(model, data, q, v),
        "centroidal_momentum_matrix_dot_times_v": lambda q, v, a: soadyn.centroidal_momentum_matrix_dot_times_v(model, data, q, v),
        "centroidal_inertia": lambda q, v, a: soadyn.centroidal_inertia(model, data, q),
        "operational_space_inertia": lambda q, v, a: soadyn.operational_space_inertia(model, data, q, J),
        "coriolis_matrix": lambda q, v, a: soadyn.coriolis_matrix(model, data, q, v),
        "regressor": lambda q, v, a: soadyn.regressor(model, data, q, v, a),
        "forward_dynamics_parameter_derivative": lambda q, v, a: soadyn.forward_dynamics_parameter_derivative(model, data, q, v, a),
    }
    return {name: functools.partial(f, *draw()) for name, f in at.items()}


def arrays(result):
    """the arrays in what a call returned (a tuple's items), as returned"""
    items = result if isinstance(result, tuple) else (result,)
    return [x for x in items if isinstance(x, np.ndarray)]


def test_the_table_covers_every_model_data_function():
    model = soadyn.load(FRAME_URDF)
    data = model.create_data()
    z = np.zeros(model.nv)
    table = calls(model, data, lambda: (model.neutral(), z, z), np.zeros((3, model.nv)))
    missing = sorted(set(stub_functions()) - set(table))
    assert not missing, f"add these to calls() so their overwrites are tested: {missing}"


@pytest.mark.parametrize("second", ["each", "all"])
def test_a_returned_result_changes_only_under_its_own_function(rng, second):
    model = soadyn.load(FRAME_URDF)
    data = model.create_data()
    J = soadyn.frame_jacobian(model, data, model.neutral(), "tool")[3:].copy()

    def state():
        return model.normalize(rng.uniform(-1.5, 1.5, model.nq)), rng.uniform(-1, 1, model.nv), rng.uniform(-2, 2, model.nv)

    kept = {}  # name: (the arrays it returned, as returned; their copies)
    changed = []
    # every function at one state, in order, then every one at another state in `second` order;
    # after each call, every result another function returned must equal its copy
    first = calls(model, data, state, J)
    later = calls(model, data, state, J)
    order = list(later) if second == "all" else list(rng.permutation(list(later)))
    for g, f in [(name, first[name]) for name in first] + [(name, later[name]) for name in order]:
        out = arrays(f())
        for name, (views, copies) in kept.items():
            if name == g:
                continue
            for k, (view, copy) in enumerate(zip(views, copies)):
                if not np.array_equal(view, copy):
                    changed.append(f"{g} changed what {name} returned (result {k})")
                    copies[k] = view.copy()  # blame the next change on its own call
        kept[g] = (out, [x.copy() for x in out])
    assert not changed, "\n".join(sorted(set(changed)))
