# Type stubs of the soadyn package (the compiled soadyn._soadyn and the pure-Python parts).
# tests/python/test_api.py checks that they name every public object with the runtime's parameters.
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt
from typing_extensions import deprecated

ArrayLike = npt.ArrayLike  # any float64 array is read in place; anything else is converted once
Vector = npt.NDArray[np.float64]

__version__: str
JOINT_TYPES: Tuple[str, ...]
METHODS: Tuple[str, ...]
DYNAMICS: Tuple[str, ...]

class Error(ValueError): ...

class Model:
    nq: int
    nv: int
    nbodies: int
    lower: List[float]
    upper: List[float]
    body_names: List[str]
    warnings: List[str]
    joint_names: List[str]
    parents: List[int]
    idx_q: List[int]
    idx_v: List[int]
    depth: int
    @property
    def joint_types(self) -> List[str]: ...
    @property
    def q_names(self) -> List[str]: ...
    @property
    def v_names(self) -> List[str]: ...
    @property
    def gravity(self) -> Vector: ...
    @property
    def masses(self) -> Vector: ...
    @property
    def coms(self) -> Vector: ...
    @property
    def inertias(self) -> Vector: ...
    @property
    def axes(self) -> Vector: ...
    @property
    def pitches(self) -> Vector: ...
    def create_data(self) -> Data: ...
    def neutral(self) -> Vector: ...
    def normalize(self, q: ArrayLike) -> Vector: ...
    def integrate(self, q: ArrayLike, v: ArrayLike, h: float) -> Vector: ...
    def qdot(self, q: ArrayLike, v: ArrayLike) -> Vector: ...
    def velocity(self, q: ArrayLike, qd: ArrayLike) -> Vector: ...
    def body_index(self, name: str) -> int: ...
    def joint_index(self, name: str) -> int: ...
    frame_names: List[str]
    frame_bodies: List[int]
    def frame_index(self, name: str) -> int: ...
    def add_frame(self, name: str, body: str, position: ArrayLike = ..., rpy: ArrayLike = ...) -> int: ...

class Data:
    def __init__(self, model: Model) -> None: ...
    model: Model
    M: Vector
    bias: Vector
    tau: Vector
    qdd: Vector
    R: Vector
    eta: Vector
    d: Vector
    s: Vector
    r: Vector
    G: Vector
    V: Vector
    Vbar: Vector
    @property
    def dtau_dq(self) -> Vector: ...
    @property
    def dtau_dv(self) -> Vector: ...
    @property
    def dqdd_dq(self) -> Vector: ...
    @property
    def dqdd_dv(self) -> Vector: ...
    @property
    def dqdd_dtau(self) -> Vector: ...
    @property
    def Minv(self) -> Vector: ...

class SimulationSettings:
    names: Tuple[str, ...]  # the settings below, from the library's one table (settings.hpp)
    words: Dict[str, Tuple[str, ...]]  # each word-valued setting's words: method, dynamics, jacobian, newton
    integration_names: Tuple[str, ...]  # those of IntegrationSettings: what a sweep's reference run may set
    def __init__(self) -> None: ...
    t_end: float
    output_dt: float
    method: str
    rtol: float
    atol: float
    dt: float
    max_step: float
    max_steps: int
    dynamics: str
    jacobian: str
    newton: str
    limits: bool
    restitution: float
    control_dt: float

class Inputs:
    @property
    def torques(self) -> List[Dict[str, Union[str, int, float]]]: ...
    @property
    def springs(self) -> List[Dict[str, Union[str, int, float]]]: ...
    @property
    def dampers(self) -> List[Dict[str, Union[str, int, float]]]: ...
    def evaluate(self, t: float, q: ArrayLike, v: ArrayLike) -> Vector: ...
    def spring_energy(self, q: ArrayLike) -> float: ...
    def __len__(self) -> int: ...

class Scenario:
    @property
    def model(self) -> Model: ...
    q0: Vector
    v0: Vector
    @property
    def inputs(self) -> Inputs: ...
    settings: SimulationSettings
    name: str
    description: str
    path: str
    text: str
    @property
    def loop_rows(self) -> List[str]: ...
    @property
    def loop_units(self) -> List[str]: ...

class RunSummary:
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
    events: List[dict]
    control_ticks: int
    stiffness_index: float
    stiffness_hint: str

class FramePoses:
    position: Vector
    orientation: Vector
    @property
    def rotation(self) -> Vector: ...

class Sensitivities:
    initial_state: Optional[Vector]
    parameters: Optional[Vector]
    state_names: List[str]
    state_units: List[str]
    parameter_names: List[str]
    parameter_units: List[str]

class Gradient:
    cost: float
    initial_state: Optional[Vector]
    parameters: Optional[Vector]
    state_names: List[str]
    parameter_names: List[str]
    stats: Dict[str, float]

class Cost:
    def __init__(self, running: Optional[Callable[[float, Vector, Vector], Tuple[float, ArrayLike, ArrayLike]]] = None,
                 terminal: Optional[Callable[[Vector, Vector], Tuple[float, ArrayLike, ArrayLike]]] = None) -> None: ...
    @property
    def has_running(self) -> bool: ...
    @property
    def has_terminal(self) -> bool: ...

class Trajectory:
    t: Vector
    q: Vector
    v: Vector
    qdd: Vector
    kinetic_energy: Vector
    potential_energy: Vector
    total_energy: Vector
    work_inputs: Vector
    dissipated: Vector
    linear_momentum: Vector
    angular_momentum: Vector
    body_position: Vector
    body_orientation: Vector
    body_com: Vector
    summary: RunSummary
    joint_names: List[str]
    parents: List[int]
    scenario: str
    frames: Dict[str, FramePoses]
    sensitivities: Optional[Sensitivities]
    ARRAYS: Tuple[str, ...]
    def __len__(self) -> int: ...
    @property
    def energy_error(self) -> Vector: ...
    @property
    def balance_error(self) -> Vector: ...

def load(path: str, free_root: bool = False, gravity: Optional[ArrayLike] = None,
         inertia_check: Optional[str] = None) -> Model: ...
def load_scenario(path: str, free_root: bool = False, gravity: Optional[ArrayLike] = None,
                  inertia_check: Optional[str] = None) -> Scenario: ...
def parse_scenario(text: str, path: str = "<string>", inertia_check: Optional[str] = None) -> Scenario: ...
def update_kinematics(model: Model, data: Data, q: ArrayLike) -> None: ...
def update_velocities(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> None: ...
def mass_matrix(model: Model, data: Data, q: ArrayLike, kinematics: bool = True) -> Vector: ...
def mass_matrix_literal(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def minverse(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def bias_forces(model: Model, data: Data, q: ArrayLike, v: ArrayLike, kinematics: bool = True) -> Vector: ...
def inverse_dynamics(model: Model, data: Data, q: ArrayLike, v: ArrayLike, qdd: ArrayLike) -> Vector: ...
def forward_dynamics(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike,
                     method: str = "aba") -> Vector: ...
def jacobian(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def inverse_dynamics_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike,
                                 qdd: ArrayLike) -> Tuple[Vector, Vector]: ...
def forward_dynamics_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike,
                                 tau: ArrayLike) -> Tuple[Vector, Vector, Vector]: ...
def loop_forward_dynamics(scene: Scenario, q: ArrayLike, v: ArrayLike,
                          tau: Optional[ArrayLike] = None) -> Tuple[Vector, Vector]: ...
def loop_inverse_dynamics(scene: Scenario, q: ArrayLike, v: ArrayLike, qdd: ArrayLike,
                          actuated: Sequence[Union[str, int]]) -> Tuple[Vector, Vector, Vector]: ...
# the old names, kept one release (a DeprecationWarning when called)
@deprecated("use bias_forces")
def bias(model: Model, data: Data, q: ArrayLike, v: ArrayLike, kinematics: bool = True) -> Vector: ...
@deprecated("use inverse_dynamics_derivatives")
def id_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike, qdd: ArrayLike) -> Tuple[Vector, Vector]: ...
@deprecated("use forward_dynamics_derivatives")
def fd_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike,
                   tau: ArrayLike) -> Tuple[Vector, Vector, Vector]: ...
def kinetic_energy(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> float: ...
def potential_energy(model: Model, data: Data, q: ArrayLike) -> float: ...
def momentum(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> Tuple[Vector, Vector]: ...
def body_poses(model: Model, q: ArrayLike) -> Tuple[Vector, Vector]: ...
Frame = Union[str, int]  # a frame's name or index
def frame_placement(model: Model, data: Data, q: ArrayLike, frame: Frame) -> Tuple[Vector, Vector]: ...
# Spatial rows are [angular; linear] ([ω; v], the note's order; Pinocchio puts linear first, so its
# J[:3] is the angular rows here): part="linear" gives rows 3-5 alone, part="angular" rows 0-2.
def frame_velocity(model: Model, data: Data, q: ArrayLike, v: ArrayLike, frame: Frame,
                   reference: str = "local_world_aligned", part: str = "all") -> Vector: ...
def frame_acceleration(model: Model, data: Data, q: ArrayLike, v: ArrayLike, qdd: ArrayLike, frame: Frame,
                       reference: str = "local_world_aligned", classical: bool = False, part: str = "all") -> Vector: ...
def frame_jacobian(model: Model, data: Data, q: ArrayLike, frame: Frame, reference: str = "local_world_aligned",
                   part: str = "all") -> Vector: ...
def frame_jacobian_dot_times_v(model: Model, data: Data, q: ArrayLike, v: ArrayLike, frame: Frame,
                               reference: str = "local_world_aligned", part: str = "all") -> Vector: ...
def point_jacobian(model: Model, data: Data, q: ArrayLike, body: Union[str, int], point: ArrayLike) -> Vector: ...
def com(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def com_velocity(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> Vector: ...
def com_jacobian(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def centroidal_momentum_matrix(model: Model, data: Data, q: ArrayLike) -> Vector: ...
def centroidal_momentum(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> Vector: ...
def centroidal_momentum_matrix_dot_times_v(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> Vector: ...
def centroidal_inertia(model: Model, data: Data, q: ArrayLike) -> Tuple[float, Vector]: ...
def operational_space_inertia(model: Model, data: Data, q: ArrayLike, J: ArrayLike) -> Vector: ...
def coriolis_matrix(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> Vector: ...
def parameters(model: Model) -> Vector: ...
def with_parameters(model: Model, pi: ArrayLike) -> Model: ...
def regressor(model: Model, data: Data, q: ArrayLike, v: ArrayLike, qdd: ArrayLike) -> Vector: ...
def forward_dynamics_parameter_derivative(model: Model, data: Data, q: ArrayLike, v: ArrayLike,
                                          tau: ArrayLike) -> Vector: ...
def simulate(scene: Union[Scenario, str], method: Optional[str] = None, *, rtol: Optional[float] = None,
             atol: Optional[float] = None, dt: Optional[float] = None, t_end: Optional[float] = None,
             output_dt: Optional[float] = None, dynamics: Optional[str] = None, jacobian: Optional[str] = None,
             newton: Optional[str] = None, max_step: Optional[float] = None, max_steps: Optional[int] = None,
             limits: Optional[bool] = None, restitution: Optional[float] = None, control_dt: Optional[float] = None,
             output: Optional[str] = None,
             controller: Optional[Callable[[float, np.ndarray, np.ndarray], ArrayLike]] = None,
             sensitivities: Optional[Dict[str, object]] = None,
             prescribed: Optional[Dict[str, Callable[[float], Tuple[float, float, float]]]] = None) -> Trajectory: ...
def read_log(path: str) -> Trajectory: ...
def tracking_cost(model: Model, reference: Union[Trajectory, str], q: object = 1.0, v: object = 0.0,
                  q_final: object = 0.0, v_final: object = 0.0) -> Cost: ...
def gradient(scene: Union[Scenario, str], cost: Cost, wrt: Union[str, Sequence[str]] = ("initial_state", "parameters"), *,
             parameters: Union[str, Sequence[str]] = "all", method: Optional[str] = None, rtol: Optional[float] = None,
             atol: Optional[float] = None, t_end: Optional[float] = None, dynamics: Optional[str] = None,
             jacobian: Optional[str] = None, steps_per_checkpoint: int = 1000) -> Gradient: ...
def rollout(scene: Union[Model, Scenario, str], initial_states: ArrayLike, controls: Optional[object] = None, *,
            steps: Optional[int] = None, dt: Optional[float] = None, method: Optional[str] = None, threads: int = 1,
            dynamics: Optional[str] = None, rtol: Optional[float] = None, atol: Optional[float] = None,
            energies: bool = True) -> Tuple[Vector, Optional[Vector]]: ...

# ensembles (soadyn.ensemble describes the sweep file)
class Sweep:
    path: str
    scenario_path: str
    cases: List[dict]
    paths: List[str]
    settings: dict
    reference: Optional[dict]
    def scenario(self, case: dict, settings: bool = True) -> Scenario: ...
    def fingerprint(self) -> str: ...

class SweepResult:
    table: dict
    path: str
    ran: int
    skipped: int
    failed: int
    wall_seconds: float

def load_sweep(path: str) -> Sweep: ...
def sweep(path: Union[str, Sweep], out: Optional[str] = None, *, scheduler: object = None,
          workers: Optional[int] = None, batch_size: Optional[int] = None, keep_logs: bool = False,
          quiet: bool = False, drop_bad_parts: bool = False, force: bool = False) -> SweepResult: ...
def read_results(path: str) -> dict: ...

# identification (include/soadyn/identify.hpp)
class Identification:
    method: str
    names: List[str]
    units: List[str]
    prior: Vector
    fitted: Vector
    standard_errors: Vector
    rows: int
    rank: int
    iterations: int
    singular_values: Vector
    unidentifiable: Vector
    unidentifiable_text: List[str]
    sigma2: float
    rms_prior: float
    rms_fitted: float
    model: Model
    scenario_text: str
    scenario: Scenario
    def value(self, name: str) -> float: ...

def identify(scene: Union[Scenario, str], data: Union[str, Trajectory, Dict[str, ArrayLike]],
             parameters: Union[str, Sequence[str]], *, method: str = "auto", tau: Optional[ArrayLike] = None,
             rank_tolerance: float = 1e-8, max_iterations: int = 20, window: float = 0.1,
             output: Optional[str] = None) -> Identification: ...
