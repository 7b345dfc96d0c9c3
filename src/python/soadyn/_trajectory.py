"""Trajectory and RunSummary: what soadyn.simulate returns and soadyn.read_log reads back."""
from dataclasses import dataclass, field, fields
from typing import Dict, List, Optional

import numpy as np


@dataclass(frozen=True)
class RunSummary:
    """How a run went: its method, solver statistics, status and energy drift.

    status is "completed", "interrupted by SIGINT at t = …", or the error that ended the run
    (completed is then False and t_reached the time of the last sample).  The energy-balance errors
    are max |E(t) − E(0) − W(t) − W_p(t) + L(t)| over the samples relative to the run's energy scale
    max(|E(0)|, peak T, peak |W|, peak |W_p|) (W the work of the torques and dampers, zero without
    them; W_p the prescribed joints'; L the impacts' loss), and that ratio at the last one.
    """
    method: str
    status: str
    completed: bool
    t_reached: float
    steps: int
    rhs_evals: int
    jac_evals: int
    error_test_failures: int
    nonlinear_iterations: int
    cpu_seconds: float
    quaternion_handling: str
    output_dt: float
    max_energy_balance_error: float
    final_energy_balance_error: float
    # joint-limit events (simulation: limits: true), each a dict t, joint, side ("lower" | "upper"),
    # kind ("impact" | "hold" | "release"), v_before, v_after, energy_lost; and a sampled
    # controller's evaluations (read_log: from the file's /events and /solver, as the run returned them)
    events: List[dict] = field(default_factory=list)
    control_ticks: int = 0
    # a cvode-adams run of 2000 steps or more: h̄ ρ, the mean step times the spectral radius of
    # ∂f/∂y (0 when not estimated), and when it is ≥ 0.2 the hint that the run was stiff and
    # cvode-bdf would take far fewer steps ("" otherwise; include/soadyn/sim/simulate.hpp)
    stiffness_index: float = 0.0
    stiffness_hint: str = ""


@dataclass(frozen=True, eq=False)
class FramePoses:
    """One logged frame's pose at every sample (a scenario's `log: {frames: [...]}`, the run
    file's /frames): position (T, 3), its origin in inertial coordinates (m); orientation (T, 4),
    the unit quaternion [w x y z] (w ≥ 0) of its attitude, frame → inertial; rotation (T, 3, 3)
    the same as matrices, R @ x taking frame coordinates to inertial ones: at each sample what
    soadyn.frame_placement(model, data, q, name) gives."""
    position: np.ndarray
    orientation: np.ndarray

    @property
    def rotation(self) -> np.ndarray:
        w, x, y, z = (self.orientation[:, k] for k in range(4))
        R = np.empty((len(w), 3, 3))
        R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
        R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
        R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
        return R


@dataclass(frozen=True, eq=False)
class Sensitivities:
    """A run's forward sensitivities (CVODES, under its error control), at every sample:
    initial_state (T, nx, nx), ∂x(t)/∂x₀, and parameters (T, nx, np), ∂x(t)/∂π (None when not
    asked for), with x = [q along the tangent; v] (nx = 2 nv, the prescribed joints' DOFs left
    out: their motion is given; a free root's q increment is
    [δθ; δp], the attitude turned about inertial axes, a ball's δθ in the child's axes) and π the
    inertial parameters of the bodies named (10 each: m, m c, the inertia about the body frame's
    origin, as soadyn.parameters orders them).  state_names, parameter_names and their SI units."""
    initial_state: Optional[np.ndarray]
    parameters: Optional[np.ndarray]
    state_names: List[str]
    state_units: List[str]
    parameter_names: List[str]
    parameter_units: List[str]


@dataclass(frozen=True, eq=False)
class Gradient:
    """A run's cost G and its gradient by the adjoint (soadyn.gradient): initial_state (2 nv,),
    ∂G/∂x₀ with x = [q along the tangent; v] as in Sensitivities, and parameters (10 per body
    asked for), ∂G/∂π; None when not asked for.  stats: the forward and backward runs' steps and
    right-hand-side evaluations, the checkpoints, the CPU seconds of both."""
    cost: float
    initial_state: Optional[np.ndarray]
    parameters: Optional[np.ndarray]
    state_names: List[str]
    parameter_names: List[str]
    stats: dict


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A run's samples as numpy arrays, T samples at the output times.

    t (T,), q (T, nq), v (T, nv) (the note's q̇), qdd (T, nv), kinetic_energy, potential_energy
    (joint springs included) and total_energy (T,), work_inputs (the work of torques and dampers
    since t = 0) and dissipated (the dampers' share, ≥ 0) (T,), linear_momentum and
    angular_momentum (T, 3) (about the inertial origin), body_position and body_com (T, N, 3) and
    body_orientation (T, N, 4, [w x y z], body → inertial); joint_names and parents of the model,
    the scenario's text, and the run's summary (a RunSummary).  A log written without a group
    (`soadyn run --log`) gives NaN for its series.  frames: the logged frames by name (read_log
    only; a FramePoses each: position, orientation, rotation), {} when the run logged none.
    """
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    qdd: np.ndarray
    kinetic_energy: np.ndarray
    potential_energy: np.ndarray
    total_energy: np.ndarray
    work_inputs: np.ndarray
    dissipated: np.ndarray
    linear_momentum: np.ndarray
    angular_momentum: np.ndarray
    body_position: np.ndarray
    body_orientation: np.ndarray
    body_com: np.ndarray
    summary: RunSummary
    joint_names: List[str] = field(default_factory=list)
    parents: List[int] = field(default_factory=list)
    scenario: str = ""
    frames: Dict[str, FramePoses] = field(default_factory=dict)
    # impact_loss (T,), L(t), the kinetic energy joint-limit impacts took since t = 0
    # (E(t) − E(0) = W(t) − L(t)), zeros without limits; control (T, nv), the controllers' torque
    # at each sample (the held value when sampled), zeros without controllers.  read_log: the file's
    # /energy/impact_loss and /control (None from a file written before layout 5 that lacks them)
    impact_loss: Optional[np.ndarray] = None
    control: Optional[np.ndarray] = None
    # simulation: sensitivities (simulate and read_log): a Sensitivities, None without them
    sensitivities: Optional[Sensitivities] = None
    # prescribed motion: the torques (N m or N) that hold the prescribed joints' motion (T, joints),
    # those joints' names, and W_p (T,), the torques' work since t = 0 (E − E(0) = W + W_p − L);
    # (T, 0), [] and zeros without prescribed joints
    prescribed_torque: Optional[np.ndarray] = None
    prescribed_joints: List[str] = field(default_factory=list)
    work_prescribed: Optional[np.ndarray] = None
    # closed loops: their multipliers λ (T, rows), N or N m, the force along each row's direction
    # (loop_rows: "<loop>.<part>", part x y z for the points' coincidence, n1 n2 a hinge's axes,
    # rx ry rz a weld's turn, tension a distance's), and the largest closure error |φ| (T,);
    # (T, 0), [] and zeros without loops
    loop_forces: Optional[np.ndarray] = None
    loop_rows: List[str] = field(default_factory=list)
    loop_closure: Optional[np.ndarray] = None

    ARRAYS = ("t", "q", "v", "qdd", "kinetic_energy", "potential_energy", "total_energy", "work_inputs", "dissipated",
              "linear_momentum", "angular_momentum", "body_position", "body_orientation", "body_com")

    def __len__(self) -> int:
        return len(self.t)

    @property
    def energy_error(self) -> np.ndarray:
        """(E(t) − E(0)) / max(|E(0)|, peak T over the run), shape (T,): the drift the summary's figures
        are taken from."""
        E, T = self.total_energy, self.kinetic_energy
        if len(E) == 0:
            return E.copy()
        return (E - E[0]) / energy_scale(E, T)

    @property
    def balance_error(self) -> np.ndarray:
        """(E(t) − E(0) − W(t) − W_p(t) + L(t)) / the run's energy scale max(|E(0)|, peak T, peak |W|,
        peak |W_p|), shape (T,): W the inputs' work, W_p the prescribed joints' torques', L the
        impacts' loss; the summary's figures are taken from it (equal to energy_error without
        torques, dampers, prescribed motion or limits)."""
        E, T = self.total_energy, self.kinetic_energy
        if len(E) == 0:
            return E.copy()
        lost = 0.0 if self.impact_loss is None else self.impact_loss
        held = np.zeros_like(E) if self.work_prescribed is None else self.work_prescribed
        return (E - E[0] - self.work_inputs - held + lost) / energy_scale(E, T, self.work_inputs, held)

    def __repr__(self) -> str:
        s = self.summary
        span = f"t = {self.t[0]:g} … {self.t[-1]:g} s" if len(self.t) else "no samples"
        return (f"<soadyn.Trajectory: {len(self)} samples, {span}, nq = {self.q.shape[1]}, nv = {self.v.shape[1]}, "
                f"{s.method}: {s.status}>")


def summary_from_dict(d: dict) -> RunSummary:
    return RunSummary(**{f.name: d[f.name] for f in fields(RunSummary)})


def energy_scale(E: np.ndarray, T: np.ndarray, *work: np.ndarray) -> float:
    """the run's energy scale max(|E(0)|, peak T, peak |W| of each work), as simulate() measures the
    energy balance against (a run from rest with E(0) = 0 against the energy brought in)"""
    scale = max(abs(float(E[0])), float(np.max(T)))
    for W in work:
        if len(W):
            scale = max(scale, float(np.max(np.abs(W))))
    return max(scale, 1e-300)


def balance_errors(total: np.ndarray, kinetic: np.ndarray, work: np.ndarray, lost: np.ndarray):
    """(max, final) relative energy-balance error, as simulate() gives them (only for files from
    before /solver kept them)"""
    if len(total) == 0:
        return 0.0, 0.0
    r = np.abs(total - total[0] - work + lost) / energy_scale(total, kinetic, work)
    return float(r.max()), float(r[-1])


def _events(c: dict) -> List[dict]:
    """/events (E × 7: t, dof, side, kind, v_before, v_after, energy_lost) as simulate() gives them"""
    kinds, idx, names = ("impact", "hold", "release"), c["joint_v_index"], c["joint_names"]
    out = []
    for t, dof, side, kind, before, after, lost in c["events"]:
        # the joint whose DOFs hold `dof` (/model joint_v_index), or the DOF's own name in older files
        owner = [k for k, first in enumerate(idx) if 0 <= first <= dof]
        joint = (names[max(owner, key=lambda k: idx[k])] if owner and len(names) == len(idx)
                 else c["v_names"][dof] if dof < len(c["v_names"]) else str(dof))
        out.append(dict(t=t, joint=joint, side="lower" if side < 0 else "upper",
                        kind=kinds[kind] if 0 <= kind < 3 else "unknown", v_before=before, v_after=after,
                        energy_lost=lost))
    return out


def read_log(path: str) -> Trajectory:
    """The Trajectory of a soadyn HDF5 run file (soadyn.simulate(output=…) or `soadyn run`).

    The same arrays as the run returned (float64 round-trips exactly), impact_loss and control
    included, and its summary as the file's /solver and /events keep it (the run's own figures:
    energy-balance errors, events, control ticks); a run still being written or cut short gives
    what was flushed.  Read by the library's reader (run_file.hpp), as `soadyn export` and
    `soadyn view` read it.
    Raises soadyn.Error when the file is missing or is not a soadyn run.
    """
    from . import Error, _soadyn

    try:  # the reason a file cannot be read (missing, a directory, a FIFO, …) is the reader's
        c = _soadyn._read_run_file(path)
    except Error as e:
        why = str(e)
        why = why[len(path) + 2:] if why.startswith(f"{path}: ") else why
        raise Error(f"{path}: cannot read the run file: {why}") from None
    logged, solver = c["series"], c["solver"]
    nq, nv, nb = c["nq"], c["nv"], len(c["body_names"])
    t = logged["/time"]
    T = len(t)

    def series(name, *shape):
        """a view's array (T, *shape), or NaN where the run did not log it"""
        return logged[name] if name in logged else np.full((T,) + shape, np.nan)

    q, v = series("/q", nq), series("/qd", nv)
    # files from before the energy balance (layout 2) hold the energies but no work: W = D = 0
    old = "/energy/total" in logged and "/energy/work_inputs" not in logged
    work = np.zeros(T) if old else series("/energy/work_inputs")
    arrays = dict(t=t, q=q, v=v, qdd=series("/qdd", v.shape[1]),
                  kinetic_energy=series("/energy/kinetic"), potential_energy=series("/energy/potential"),
                  total_energy=series("/energy/total"), work_inputs=work,
                  dissipated=np.zeros(T) if old else series("/energy/dissipated"),
                  linear_momentum=series("/momentum/linear", 3), angular_momentum=series("/momentum/angular", 3),
                  body_position=series("/bodies/position", nb, 3), body_orientation=series("/bodies/orientation", nb, 4),
                  body_com=series("/bodies/com", nb, 3))
    # L(t) and τ: the file's, zeros where the run had no limits or controllers (as simulate gives
    # them); None in a file from before layout 5 that lacks them
    logged_energy, new = "/energy/total" in logged, c["layout_version"] >= 5
    impact_loss = logged.get("/energy/impact_loss", np.zeros(T) if logged_energy and new else None)
    control = logged.get("/control", np.zeros((T, nv)) if new else None)
    status = solver["status"] or "unknown"
    # the run's own figures (/solver, layout 3 on); files from before: recomputed from the energies
    if c["layout_version"] >= 3:
        worst, last = solver["max_energy_balance_error"], solver["final_energy_balance_error"]
    else:
        worst, last = balance_errors(arrays["total_energy"], arrays["kinetic_energy"], arrays["work_inputs"],
                                     np.zeros(T) if impact_loss is None else impact_loss)
    summary = RunSummary(
        method=solver["method"], status=status, completed=status == "completed", t_reached=solver["t_reached"],
        steps=solver["steps"], rhs_evals=solver["rhs_evals"], jac_evals=solver["jac_evals"],
        error_test_failures=solver["error_test_failures"], nonlinear_iterations=solver["nonlinear_iterations"],
        cpu_seconds=solver["cpu_seconds"], quaternion_handling=solver["quaternion_handling"],
        output_dt=solver["output_dt"], max_energy_balance_error=worst, final_energy_balance_error=last,
        events=_events(c), control_ticks=solver["control_ticks"], stiffness_index=solver["stiffness_index"],
        stiffness_hint=solver["stiffness_hint"])
    # /frames: names (F), position (T, F, 3), orientation (T, F, 4)
    fnames = c["frame_names"]
    pos, att = series("/frames/position", len(fnames), 3), series("/frames/orientation", len(fnames), 4)
    frames = {n: FramePoses(position=pos[:, k].copy(), orientation=att[:, k].copy()) for k, n in enumerate(fnames)}
    # /sensitivities: initial_state (T, nx, nx), parameters (T, nx, np), names on the group
    sensitivities = None
    if c["state_names"] or any(k.startswith("/sensitivities/") for k in logged):
        sensitivities = Sensitivities(
            initial_state=logged.get("/sensitivities/initial_state"), parameters=logged.get("/sensitivities/parameters"),
            state_names=c["state_names"], state_units=c["state_units"],
            parameter_names=c["parameter_names"], parameter_units=c["parameter_units"])
    # /prescribed (T, joints) with the joints from its columns' names, and W_p; as simulate gives
    # them ((T, 0), zeros) when the run prescribed nothing
    held = [n[len("prescribed."):] for n in c["column_names"] if n.startswith("prescribed.")]
    prescribed_torque = logged.get("/prescribed", np.zeros((T, 0)))
    work_prescribed = logged.get("/energy/work_prescribed", np.zeros(T) if logged_energy else None)
    # /loops/force (T, rows) with the rows from its columns' names, and /loops/closure
    rows = [n[len("loops.force."):] for n in c["column_names"] if n.startswith("loops.force.")]
    loop_forces = logged.get("/loops/force", np.zeros((T, 0)))
    loop_closure = logged.get("/loops/closure", np.zeros(T))
    return Trajectory(**arrays, summary=summary, joint_names=c["joint_names"], parents=c["parents"],
                      scenario=c["scenario"], frames=frames, impact_loss=impact_loss, control=control,
                      sensitivities=sensitivities, prescribed_torque=prescribed_torque, prescribed_joints=held,
                      work_prescribed=work_prescribed, loop_forces=loop_forces, loop_rows=rows, loop_closure=loop_closure)
