"""soadyn.identify: inertial parameters fitted to a logged motion (include/soadyn/sim/identify.hpp)."""
import os
from dataclasses import dataclass, field
from typing import List, Optional, Sequence, Union

import numpy as np


@dataclass
class Identification:
    """What soadyn.identify fitted.

    names, units: the fitted parameters, 10 per body ("<body>.m", ".mcx", ".mcy", ".mcz", ".Ixx",
    ".Ixy", ".Iyy", ".Ixz", ".Iyz", ".Izz": mass, first moment m c, inertia about the body origin,
    body axes).  prior: the scene's values; fitted; standard_errors (σ̂ √diag((AᵀA)⁺), column-scaled).
    rank of the stacked system (rows equations); singular_values of the column-scaled system;
    unidentifiable (np, k): directions in π the data cannot see, held at the scene's values, and
    unidentifiable_text, the same as "0.5 link2.m + link2.Ixx".  sigma2 = |residual|² / (rows −
    rank); rms_prior, rms_fitted: the residual's RMS before and after.  model: the scene's model with
    the fitted parameters; scenario: the fitted scene (scenario_text, its YAML, with `inertial:`).
    """
    method: str
    names: List[str]
    units: List[str]
    prior: np.ndarray
    fitted: np.ndarray
    standard_errors: np.ndarray
    rows: int
    rank: int
    iterations: int
    singular_values: np.ndarray
    unidentifiable: np.ndarray
    unidentifiable_text: List[str]
    sigma2: float
    rms_prior: float
    rms_fitted: float
    model: object
    scenario_text: str
    scenario: object = field(default=None, repr=False)

    def value(self, name: str) -> float:
        """the fitted value of one parameter, e.g. value("link2.m")"""
        return float(self.fitted[self.names.index(name)])


def identify(scene, data, parameters: Union[str, Sequence[str]], *, method: str = "auto", tau=None,
             rank_tolerance: float = 1e-8, max_iterations: int = 20, window: float = 0.1,
             output: Optional[str] = None) -> Identification:
    """Fit the inertial parameters of the bodies `parameters` (names, or "all") of `scene` (a
    Scenario or a scenario path) to the motion `data`, the other bodies held at the scene's values.

    data: a run file's path (soadyn run, simulate(output=…)), a Trajectory (simulate, read_log), or a
    dict {"t": (T,), "q": (T, nq), "v": (T, nv), "qdd": (T, nv) optional}.  tau: (T, nv) measured
    generalized forces (default: the scene's inputs at each sample).
    method: "auto" (least squares on τ = Y π when q̈ is there, else Gauss–Newton), "least-squares",
    "gauss-newton" (the logged q, v against simulations of the scene over windows of `window` s, each
    from the logged state at its start, CVODES sensitivities as the Jacobian, damped until the
    residual falls; a step that leaves the rigid bodies is refused, so a fit far off may stall).  rank_tolerance: singular values of the column-scaled system below this times the
    largest count as zero; those directions are reported, not fitted.  output: where the fitted
    scene will be written (its robot file's path is made relative to it; default: the scene's own
    directory).  Returns an Identification.  Raises soadyn.Error naming what is wrong: an unknown
    body, data that do not fit the scene, a fit that is no rigid body (the body named).
    """
    from . import Error, Trajectory, load_scenario, parse_scenario, _soadyn

    if isinstance(scene, (str, os.PathLike)):
        scene = load_scenario(str(scene))
    bodies = [parameters] if isinstance(parameters, str) else list(parameters)
    path = t = q = v = qdd = None
    if isinstance(data, (str, os.PathLike)):
        path = str(data)
    elif isinstance(data, Trajectory):
        t, q, v, qdd = data.t, data.q, data.v, data.qdd
    elif isinstance(data, dict):
        unknown = set(data) - {"t", "q", "v", "qd", "qdd"}
        if unknown:
            raise Error(f"identify: data: unknown key '{sorted(unknown)[0]}' (expected t, q, v, qdd)")
        t, q, v, qdd = data.get("t"), data.get("q"), data.get("v", data.get("qd")), data.get("qdd")
    else:
        raise Error(f"identify: data: expected a run file's path, a Trajectory or a dict of arrays, got {type(data).__name__}")
    if qdd is not None and np.isnan(np.asarray(qdd, float)).all():
        qdd = None  # a Trajectory read from a run logged without q̈
    r = _soadyn._identify(scene, path, t, q, v, qdd, tau, bodies, method, float(rank_tolerance), int(max_iterations),
                          float(window), "" if output is None else str(output))
    out = Identification(**r)
    anchor = str(output) if output is not None else scene.path
    out.scenario = parse_scenario(out.scenario_text, anchor)
    return out
