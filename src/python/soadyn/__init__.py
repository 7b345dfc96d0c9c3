"""soadyn: dynamics of tree-structured rigid multibody systems by the note's spatial operators.

The C++ library's Model/Data split, its algorithms and its simulator, with numpy arrays in and out.

    import numpy as np, soadyn
    model = soadyn.load("robot.urdf")              # a Model: the constant tree
    data = model.create_data()                     # a Data: per-state arrays, allocated once
    M = soadyn.mass_matrix(model, data, model.neutral())
    traj = soadyn.simulate("scenarios/double_pendulum.yaml", method="rk4", t_end=2.0)

Notation (the note's): spatial vectors are [ω; v], angular first, in inertial coordinates;
q (nq,) is the configuration and v (nv,) its rates (the note's q̇; ω for a free joint's attitude).
𝓜(q) q̈ + bias(q, q̇) = τ.

Names
    JOINT_TYPES (revolute, prismatic, ball, planar, free, fixed), METHODS (the integrators),
    DYNAMICS (the forward-dynamics routes: dense, sparse, on)
Loading
    load(path, free_root=False, gravity=None) -> Model        a URDF or a scenario's model
    load_scenario(path) -> Scenario                           .model .q0 .v0 .inputs .settings
    parse_scenario(text, path="<string>") -> Scenario
Model
    nq, nv, nbodies, joint_names, joint_types, q_names, v_names, body_names, parents, gravity,
    masses, coms, inertias, axes; create_data(), neutral(), normalize(q), integrate(q, v, h),
    qdot(q, v), velocity(q, qd)
Algorithms (model, data, …), each first updating the kinematics at q (and velocities at v)
    mass_matrix(q)            𝓜 = Gᵀ Ψ_Dᵀ M Ψ_D G (eq. 14)      -> view of data.M      (nv, nv)
    mass_matrix_literal(q)    J = Ψ_D G, Q = M J, 𝓜 = Jᵀ Q       -> new array            (nv, nv)
    bias(q, v)                Gᵀ Ψ_Dᵀ (M Ψ_D a + b)              -> view of data.bias   (nv,)
    inverse_dynamics(q, v, qdd)   τ = 𝓜 q̈ + bias                 -> view of data.tau    (nv,)
    forward_dynamics(q, v, tau, method="on")  q̈ = 𝓜⁻¹(τ − bias) -> view of data.qdd    (nv,)
    jacobian(q)               J = S Ψ_D G (eq. 7)                -> new array            (6N, nv)
    kinetic_energy(q, v), potential_energy(q) -> float;  momentum(q, v) -> (linear, angular)
    update_kinematics(q), update_velocities(q, v): fill data.R, eta, d, s, r, G, V, Vbar
Simulation
    simulate(scene, method=…, rtol=…, t_end=…, output=None) -> Trajectory
    read_log(path) -> Trajectory
Ensembles (soadyn.ensemble: the sweep file's format)
    sweep(path, out=None, scheduler=None, workers=None, …) -> SweepResult   on Dask, resumable
    load_sweep(path) -> Sweep;  read_results(path) -> {column: array}

Arrays in: any float64 array is read in place whatever its strides; lists and other dtypes are
converted once.  Arrays out: data.M, data.bias, data.tau and data.qdd are read-only views into the
Data (no copy; the next call on the same Data overwrites them; each keeps the memory alive after
the Data is gone); everything else is a new array.

Errors: soadyn.Error (a ValueError) with the command line's message: file:line:column: field:
expected …, got ….
"""
import warnings as _warnings
from typing import Optional, Union

from ._soadyn import (DYNAMICS, JOINT_TYPES, METHODS, Data, Error, Inputs, Model, Scenario, SimulationSettings,
                      __version__, bias, body_poses, fd_derivatives, forward_dynamics, id_derivatives, inverse_dynamics,
                      jacobian, kinetic_energy, load,
                      load_scenario, mass_matrix, mass_matrix_literal, momentum, parse_scenario, potential_energy,
                      update_kinematics, update_velocities)
from . import _soadyn
from ._trajectory import RunSummary, Trajectory, read_log, summary_from_dict
from ._sweep import SweepResult, read_results, sweep
from .ensemble import Sweep, load_sweep

__all__ = [
    "DYNAMICS", "JOINT_TYPES", "METHODS", "Data", "Error", "Inputs", "Model", "RunSummary", "Scenario", "SimulationSettings", "Trajectory", "__version__",
    "bias", "body_poses", "fd_derivatives", "forward_dynamics", "id_derivatives", "inverse_dynamics", "jacobian",
    "kinetic_energy", "load", "load_scenario", "mass_matrix", "mass_matrix_literal", "momentum", "parse_scenario",
    "potential_energy", "read_log", "simulate", "Sweep", "SweepResult", "load_sweep", "read_results", "sweep", "update_kinematics", "update_velocities",
]

for _cls in (Data, Error, Inputs, Model, Scenario, SimulationSettings, RunSummary, Trajectory):
    _cls.__module__ = __name__  # soadyn.Model, not soadyn._soadyn.Model, in messages and help


def simulate(scene: Union[Scenario, str], method: Optional[str] = None, *, rtol: Optional[float] = None,
             atol: Optional[float] = None, dt: Optional[float] = None, t_end: Optional[float] = None,
             output_dt: Optional[float] = None, dynamics: Optional[str] = None, jacobian: Optional[str] = None,
             newton: Optional[str] = None, output: Optional[str] = None) -> Trajectory:
    """Simulate a scenario and return its Trajectory: 𝓜(q) q̈ = τ(t, q, q̇) − bias(q, q̇) from (q0, v0).

    scene: a Scenario or the path of a scenario file.  Each keyword left None keeps the scene's
    own setting (scene.settings): method (cvode-adams | cvode-bdf | rk4 | euler | semi-implicit-euler |
    symplectic-euler | implicit-midpoint), rtol, atol (CVODE), dt (fixed-step methods' step, s), t_end (s),
    output_dt (s between samples), dynamics (forward-dynamics route: on | dense | sparse),
    jacobian (CVODE BDF's Jacobian: analytic | dq), newton (implicit midpoint: full | simplified).
    output: an HDF5 file to log to as well (the layout of `soadyn run`; read_log reads it back).

    The integration runs without the GIL.  A run that fails midway does not raise: the summary
    says how it ended and the trajectory holds every sample up to then.  Ctrl-C (or any Python
    signal handler that raises) ends the run before its next integrator step, finishes the file
    (status "interrupted by SIGINT at t = …") and re-raises: the KeyboardInterrupt carries the
    partial Trajectory as .trajectory.  Raises soadyn.Error for bad settings before any file is
    written; the library's warnings about the settings become RuntimeWarnings.
    """
    if isinstance(scene, str):
        scene = load_scenario(scene)
    s = SimulationSettings()
    for k in ("t_end", "output_dt", "method", "rtol", "atol", "dt", "max_step", "max_steps", "dynamics", "jacobian",
              "newton"):
        setattr(s, k, getattr(scene.settings, k))
    for k, value in dict(method=method, rtol=rtol, atol=atol, dt=dt, t_end=t_end, output_dt=output_dt,
                         dynamics=dynamics, jacobian=jacobian, newton=newton).items():
        if value is not None:
            setattr(s, k, value)
    arrays, summary, interrupt, warns = _soadyn._simulate(scene, s, None if output is None else str(output))
    for w in warns:  # e.g. an rtol below what double precision can deliver
        _warnings.warn(w, RuntimeWarning, stacklevel=2)
    model = scene.model
    traj = Trajectory(**arrays, summary=summary_from_dict(summary), joint_names=list(model.joint_names),
                      parents=list(model.parents), scenario=scene.text)
    if interrupt is not None:
        try:
            interrupt.trajectory = traj
        except AttributeError:
            pass
        raise interrupt
    return traj


del Optional, Union, _cls
