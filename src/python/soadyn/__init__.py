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
    JOINT_TYPES (revolute, prismatic, ball, planar, free, helical, fixed), METHODS (the integrators),
    DYNAMICS (the forward-dynamics routes: dense, sparse, aba; "on", the old word for aba, is taken too)
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
    minverse(q)               𝓜⁻¹ by the articulated-body recursion -> view of data.Minv (nv, nv)
    bias_forces(q, v)         Gᵀ Ψ_Dᵀ (M Ψ_D a + b)              -> view of data.bias   (nv,)
    inverse_dynamics(q, v, qdd)   τ = 𝓜 q̈ + bias                 -> view of data.tau    (nv,)
    forward_dynamics(q, v, tau, method="aba") q̈ = 𝓜⁻¹(τ − bias) -> view of data.qdd    (nv,)
    jacobian(q)               J = S Ψ_D G (eq. 7)                -> new array            (6N, nv)
    inverse_dynamics_derivatives(q, v, qdd) -> views (data.dtau_dq, data.dtau_dv)
    forward_dynamics_derivatives(q, v, tau) -> views (data.dqdd_dq, data.dqdd_dv, data.dqdd_dtau = 𝓜⁻¹)
    kinetic_energy(q, v), potential_energy(q) -> float;  momentum(q, v) -> (linear, angular)
    update_kinematics(q), update_velocities(q, v): fill data.R, eta, d, s, r, G, V, Vbar
Frames and task space (model, data, q, …, frame, reference="local_world_aligned"), new arrays
    model.frame_names: every body, every link merged by a fixed joint, a scenario's frames: entries
    frame_placement(q, frame) -> (R, p);  frame_velocity(q, v, frame), frame_acceleration(q, v, qdd, frame)
    frame_jacobian(q, frame) (6, nv);  frame_jacobian_dot_times_v(q, v, frame);  point_jacobian(q, body, point)
    com(q), com_velocity(q, v), com_jacobian(q) (3, nv);  centroidal_momentum_matrix(q) A_G (6, nv)
    operational_space_inertia(q, J) Λ = (J 𝓜⁻¹ Jᵀ)⁻¹;  coriolis_matrix(q, v) C with C v = bias − gravity
Inertial parameters (π: 10 per body, m, m c, I about the body origin, body axes)
    parameters(model) -> π (10 N,);  with_parameters(model, π) -> Model (inconsistent π refused)
    regressor(model, data, q, v, qdd) Y (nv, 10 N), τ = Y π;  forward_dynamics_parameter_derivative(…, tau) ∂q̈/∂π
Simulation
    simulate(scene, method=…, rtol=…, t_end=…, output=None) -> Trajectory
    rollout(scene, initial_states, controls=None, steps=None, dt=…, method=…, threads=1)
        -> (states (K, T, nq + nv), energies (K, T))      K runs of T steps in one call, no GIL
Many states per call (soadyn.batch: (K, nq), (K, nv) in, (K, nv) or (K, nv, nv) out, threads=)
    batch.forward_dynamics, mass_matrix, bias_forces, inverse_dynamics, inverse_dynamics_derivatives,
    forward_dynamics_derivatives;
    batch.Pool(model, threads) keeps one Data per thread between calls: pool.forward_dynamics(q, v, tau), …
    read_log(path) -> Trajectory
Gradients of a whole run (adjoint, CVODES)
    gradient(scene, cost, wrt=("initial_state", "parameters"), parameters="all", …) -> Gradient
    Cost(running=f, terminal=phi);  tracking_cost(model, reference, q=1.0, v=0.0, q_final=0.0, v_final=0.0)
Identification (include/soadyn/sim/identify.hpp)
    identify(scene, data, parameters=[body, ...] | "all") -> Identification   fitted π, standard
        errors, the unidentifiable directions, the fitted model and scene
Ensembles (soadyn.ensemble: the sweep file's format)
    sweep(path, out=None, scheduler=None, workers=None, …) -> SweepResult   on Dask, resumable
    load_sweep(path) -> Sweep;  read_results(path) -> {column: array}

Arrays in: any float64 array is read in place whatever its strides; lists and other dtypes are
converted once.  Arrays out: data.M, data.bias, data.tau, data.qdd and the derivatives' arrays are
read-only views into the Data (no copy; each keeps the memory alive after the Data is gone), each
one function's own: a view changes only when its own function is called again on that Data (copy it
to keep it); everything else is a new array.  Spatial vectors are [angular; linear] ([ω; v]): a
frame Jacobian's rows 0–2 are angular, 3–5 linear (Pinocchio puts linear first).

Names are C++'s.  Deprecated, kept one release with a DeprecationWarning: bias (bias_forces),
id_derivatives (inverse_dynamics_derivatives), fd_derivatives (forward_dynamics_derivatives), and the
same in soadyn.batch.

Errors: soadyn.Error (a ValueError) with the command line's message: file:line:column: field:
expected …, got ….
"""
import warnings as _warnings
from typing import Callable, Optional, Union

from ._soadyn import (DYNAMICS, JOINT_TYPES, METHODS, Data, Error, Inputs, Model, Scenario, SimulationSettings,
                      __version__, bias_forces, body_poses, forward_dynamics, forward_dynamics_derivatives,
                      inverse_dynamics, inverse_dynamics_derivatives, jacobian, kinetic_energy, load,
                      load_scenario, mass_matrix, mass_matrix_literal, minverse, momentum, parse_scenario, potential_energy,
                      update_kinematics, update_velocities)
from ._soadyn import (centroidal_inertia, centroidal_momentum, centroidal_momentum_matrix,  # frames.hpp
                      centroidal_momentum_matrix_dot_times_v, com, com_jacobian, com_velocity, coriolis_matrix,
                      frame_acceleration, frame_jacobian, frame_jacobian_dot_times_v, frame_placement, frame_velocity,
                      operational_space_inertia, point_jacobian)
from ._soadyn import (forward_dynamics_parameter_derivative, parameters, regressor,  # regressor.hpp
                      with_parameters)
from ._soadyn import loop_forward_dynamics, loop_inverse_dynamics  # loops.hpp
from . import _soadyn
from ._soadyn import Cost, batch
from ._trajectory import FramePoses, Gradient, RunSummary, Sensitivities, Trajectory, read_log, summary_from_dict
from ._sweep import SweepResult, sweep
from ._sweep_store import read_results
from .ensemble import Sweep, load_sweep
from ._identify import Identification, identify

__all__ = [
    "centroidal_inertia", "centroidal_momentum", "centroidal_momentum_matrix", "centroidal_momentum_matrix_dot_times_v",
    "com", "com_jacobian", "com_velocity", "coriolis_matrix", "frame_acceleration", "frame_jacobian",
    "frame_jacobian_dot_times_v", "frame_placement", "frame_velocity", "operational_space_inertia", "point_jacobian",
    "forward_dynamics_parameter_derivative", "parameters", "regressor", "with_parameters",
    "loop_forward_dynamics", "loop_inverse_dynamics",
    "Cost", "Gradient", "gradient", "tracking_cost",
    "DYNAMICS", "JOINT_TYPES", "METHODS", "Data", "Error", "FramePoses", "Inputs", "Model", "RunSummary", "Scenario", "Sensitivities", "SimulationSettings", "Trajectory", "__version__",
    "bias", "id_derivatives", "fd_derivatives",  # deprecated: bias_forces, inverse_/forward_dynamics_derivatives
    "bias_forces", "body_poses", "forward_dynamics", "forward_dynamics_derivatives", "inverse_dynamics",
    "inverse_dynamics_derivatives", "jacobian",
    "kinetic_energy", "load", "load_scenario", "mass_matrix", "mass_matrix_literal", "minverse", "momentum", "parse_scenario",
    "potential_energy", "read_log", "Identification", "identify", "rollout", "simulate", "Sweep", "SweepResult", "load_sweep", "read_results", "sweep", "update_kinematics", "update_velocities",
]

for _cls in (Cost, Data, Error, FramePoses, Inputs, Model, Scenario, Sensitivities, SimulationSettings, RunSummary, Trajectory):
    _cls.__module__ = __name__  # soadyn.Model, not soadyn._soadyn.Model, in messages and help


def _deprecated(old: str, new: Callable, where: str = "soadyn") -> Callable:
    """`old`, kept one release: warns (DeprecationWarning, at the caller) and calls `new`."""
    def alias(*args, **kwargs):
        _warnings.warn(f"{where}.{old} is deprecated and goes in the next release: use {where}.{new.__name__}",
                       DeprecationWarning, stacklevel=2)
        return new(*args, **kwargs)
    alias.__name__ = alias.__qualname__ = old
    alias.__doc__ = f"Deprecated: {where}.{new.__name__} (the same arguments and results)."
    alias.__wrapped__ = new  # inspect.signature: the new function's parameters
    return alias


bias = _deprecated("bias", bias_forces)
id_derivatives = _deprecated("id_derivatives", inverse_dynamics_derivatives)
fd_derivatives = _deprecated("fd_derivatives", forward_dynamics_derivatives)


def _settings(scene: Scenario, overrides: dict) -> SimulationSettings:
    """The scene's own simulation settings, each override that is not None put over them."""
    s = SimulationSettings()
    for k in SimulationSettings.names + ("sensitivities",):
        setattr(s, k, getattr(scene.settings, k))
    for k, value in overrides.items():
        if value is not None:
            setattr(s, k, value)
    return s


def simulate(scene: Union[Scenario, str], method: Optional[str] = None, *, rtol: Optional[float] = None,
             atol: Optional[float] = None, dt: Optional[float] = None, t_end: Optional[float] = None,
             output_dt: Optional[float] = None, dynamics: Optional[str] = None, jacobian: Optional[str] = None,
             newton: Optional[str] = None, max_step: Optional[float] = None, max_steps: Optional[int] = None,
             limits: Optional[bool] = None, restitution: Optional[float] = None, control_dt: Optional[float] = None,
             output: Optional[str] = None, controller: Optional[Callable] = None,
             sensitivities: Optional[dict] = None, prescribed: Optional[dict] = None) -> Trajectory:
    """Simulate a scenario and return its Trajectory: 𝓜(q) q̈ = τ(t, q, q̇) − bias(q, q̇) from (q0, v0).

    scene: a Scenario or the path of a scenario file.  Each keyword left None keeps the scene's
    own setting (scene.settings): method (cvode-adams | cvode-bdf | rk4 | euler | semi-implicit-euler |
    symplectic-euler | implicit-midpoint | variational), rtol, atol (CVODE), dt (fixed-step methods' step, s), t_end (s),
    output_dt (s between samples), dynamics (forward-dynamics route: aba | dense | sparse),
    jacobian (CVODE BDF's Jacobian: analytic | dq), newton (implicit midpoint: full | simplified),
    max_step, max_steps (CVODE), limits (joint limits as events), restitution, control_dt: one keyword
    per setting of SimulationSettings.names (scenarios/README.md says what each does).
    output: an HDF5 file to log to as well (the layout of `soadyn run`; read_log reads it back).
    controller: f(t, q, v) -> tau, nv torques added to the inputs' (with the scene's built-in
    controllers): called at every right-hand-side evaluation and sample when continuous, once per
    tick when the scene's simulation has control_dt > 0 (zero-order hold).  The GIL is taken for
    the call only.  An exception it raises ends the run, finishes the file and is re-raised with
    the partial Trajectory as .trajectory; so does a tau of the wrong shape or not finite, raised
    as soadyn.Error naming the time and the value (the file keeps the rows logged until then).
    sensitivities: {"initial_state": True, "parameters": ["link2", "link3"] or "all"} (the scenario's
    simulation: sensitivities: otherwise): forward sensitivities by CVODES, in .sensitivities (a
    Sensitivities: initial_state (T, nx, nx), parameters (T, nx, np), their names); CVODE methods only,
    no controller, no enforced joint limits (soadyn.Error otherwise).
    prescribed: {"joint": f} with f(t) -> (q, qd, qdd): the joint (1-DOF) follows that motion
    (over the scene's own prescribed: for it), its start taken from f(0); the run solves the other
    joints' q̈ and the torques that hold the motion (hybrid dynamics), in .prescribed_torque
    (T, joints) with .prescribed_joints their names.  The GIL is taken for each call.

    The integration runs without the GIL.  A run that fails midway does not raise: the summary
    says how it ended and the trajectory holds every sample up to then.  Ctrl-C (or any Python
    signal handler that raises) ends the run before its next integrator step, finishes the file
    (status "interrupted by SIGINT at t = …") and re-raises: the KeyboardInterrupt carries the
    partial Trajectory as .trajectory.  Raises soadyn.Error for bad settings before any file is
    written; the library's warnings about the settings become RuntimeWarnings.
    """
    if isinstance(scene, str):
        scene = load_scenario(scene)
    s = _settings(scene, dict(method=method, rtol=rtol, atol=atol, dt=dt, t_end=t_end, output_dt=output_dt,
                              dynamics=dynamics, jacobian=jacobian, newton=newton, max_step=max_step,
                              max_steps=max_steps, limits=limits, restitution=restitution, control_dt=control_dt,
                              sensitivities=sensitivities))
    arrays, summary, interrupt, warns = _soadyn._simulate(scene, s, None if output is None else str(output),
                                                          controller, prescribed)
    for w in warns:  # e.g. an rtol below what double precision can deliver
        _warnings.warn(w, RuntimeWarning, stacklevel=2)
    if summary["stiffness_hint"]:  # said once; also in the Trajectory's summary
        _warnings.warn(summary["stiffness_hint"], RuntimeWarning, stacklevel=2)
    model = scene.model
    sens = None
    if "sensitivity_names" in arrays:
        names = arrays.pop("sensitivity_names")
        sens = Sensitivities(initial_state=arrays.pop("sensitivity_initial_state"),
                             parameters=arrays.pop("sensitivity_parameters"), state_names=list(names["state"]),
                             state_units=list(names["state_units"]), parameter_names=list(names["parameters"]),
                             parameter_units=list(names["parameter_units"]))
    traj = Trajectory(**arrays, summary=summary_from_dict(summary), joint_names=list(model.joint_names),
                      parents=list(model.parents), scenario=scene.text, sensitivities=sens)
    if interrupt is not None:
        try:
            interrupt.trajectory = traj
        except AttributeError:
            pass
        raise interrupt
    return traj


def tracking_cost(model: Model, reference, q=1.0, v=0.0, q_final=0.0, v_final=0.0) -> Cost:
    """The cost of tracking a reference motion, for soadyn.gradient:
    G = ∫ ½ Σ q_k (q_k − q̂_k(t))² + ½ Σ v_k (v_k − v̂_k(t))² dt + the same with q_final, v_final at T,
    q̂ and v̂ natural cubic splines through the reference's samples.  reference: a Trajectory (simulate,
    read_log; anything with arrays t, q and v) or the path of a run file.  Each weight: a number for every column, or one per column
    (nq for q, a quaternion's four coordinates included; nv for v); 0 or None: no such term."""
    if isinstance(reference, str):
        reference = read_log(reference)
    return _soadyn._tracking_cost(model, reference.t, reference.q, reference.v, q, v, q_final, v_final)


def gradient(scene: Union[Scenario, str], cost: Cost, wrt=("initial_state", "parameters"), *, parameters="all",
             method: Optional[str] = None, rtol: Optional[float] = None, atol: Optional[float] = None,
             t_end: Optional[float] = None, dynamics: Optional[str] = None, jacobian: Optional[str] = None,
             steps_per_checkpoint: int = 0) -> Gradient:
    """The gradient of a whole run's cost by the adjoint method (CVODES: one forward run with
    checkpoints, one backward run, whatever the number of parameters).

    cost: a soadyn.Cost (Cost(running=f, terminal=phi) from Python callables, or tracking_cost).
    wrt: "initial_state" and/or "parameters"; parameters: the bodies whose 10 inertial parameters
    each are differentiated, a list of names or "all".  The keywords override the scene's settings
    as in simulate (CVODE methods only; no controller, no enforced joint limits).  Returns a Gradient:
    cost, initial_state (2 nv, ∂G/∂x₀ along the tangent, as Sensitivities), parameters (10 per body),
    their names and the runs' counters.  The runs go without the GIL; an exception a cost callable
    raises is re-raised.  steps_per_checkpoint: CVODES' steps between checkpoints (memory: one
    interpolation point per step of one interval); 0 chooses 50 per entry of the state, 500 to 10000."""
    if isinstance(scene, str):
        scene = load_scenario(scene)
    wrt = [wrt] if isinstance(wrt, str) else list(wrt)
    unknown = [w for w in wrt if w not in ("initial_state", "parameters")]
    if unknown:
        raise Error(f"gradient: wrt: expected 'initial_state' and/or 'parameters', got {unknown[0]!r}")
    bodies = [] if "parameters" not in wrt else (["all"] if parameters == "all" else list(parameters))
    s = _settings(scene, dict(method=method, rtol=rtol, atol=atol, t_end=t_end, dynamics=dynamics, jacobian=jacobian))
    out = _soadyn._gradient(scene, s, cost, "initial_state" in wrt, bodies, int(steps_per_checkpoint))
    return Gradient(cost=out["cost"], initial_state=out["initial_state"] if "initial_state" in wrt else None,
                    parameters=out["parameters"] if bodies else None, state_names=list(out["state_names"]),
                    parameter_names=list(out["parameter_names"]),
                    stats={k: out[k] for k in ("forward_steps", "backward_steps", "checkpoints", "forward_rhs_evals",
                                               "backward_rhs_evals", "cpu_seconds")})


def rollout(scene, initial_states, controls=None, *, steps: Optional[int] = None, dt: Optional[float] = None,
            method: Optional[str] = None, threads: int = 1, dynamics: Optional[str] = None,
            rtol: Optional[float] = None, atol: Optional[float] = None, energies: bool = True):
    """K simulations of T steps in one call: (states, energies).

    scene: a Model (no inputs; rk4 at dt = 1e-3 unless told), a Scenario or a scenario path (its
    inputs and its settings: method, dt, rtol, atol, dynamics); a scene with built-in controllers
    or enforced joint limits (limits: true), which rollout does not apply, is refused (soadyn.Error:
    simulate runs them).  initial_states: (K, nq + nv), one [q, v] per rollout (quaternions within
    1e-6 of unit norm, then normalized; others refused).  controls: None; an array (K, T, nv), the
    generalized force u[k, s] added to the inputs' over step s of rollout k; or a callable
    controls(k, s, t, y) -> (nv,) called before each step with the state y (nq + nv,) (then
    steps= is required; it runs with the GIL, so it serializes threads).  dt: the step of fixed-step
    methods and the interval of the controls and of the output; CVODE (method cvode-adams or
    cvode-bdf) advances to each step's end under rtol/atol and restarts where the control changes.

    Returns states (K, T, nq + nv), the state of rollout k after step s at t = (s + 1)·dt, and
    energies (K, T), the total energy T + V (+ springs) there (None with energies=False).  The
    rollouts run without the GIL on `threads` threads (0: one per core); each rollout's states are
    the same whatever the thread count, and those of simulate() with output_dt = dt.  A rollout
    that fails (unstable) is NaN from there on, with a RuntimeWarning saying why.  Ctrl-C ends
    every rollout before its next step and re-raises.  Bad shapes raise soadyn.Error (a
    ValueError) naming the argument and the expected shape.
    """
    states, energy, status, interrupt = _soadyn._rollout(scene, initial_states, controls, steps, dt, method, threads,
                                                         dynamics, rtol, atol, energies)
    if interrupt is not None:
        raise interrupt
    failed = [(k, s) for k, s in enumerate(status) if s != "completed"]
    if failed:
        _warnings.warn(f"rollout: {len(failed)} of {len(status)} rollouts failed (NaN from there on); "
                       f"rollout {failed[0][0]}: {failed[0][1]}", RuntimeWarning, stacklevel=2)
    return states, energy


del Optional, Union, _cls
