"""Shared by tools/work_precision.py and tools/stability.py: one run, in this process through the
soadyn Python module when it is built (beside the executable: build/python), else by `soadyn run`
and its file.  SOADYN_RUNS_CLI=1 forces the executable."""
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
SCENARIOS = os.path.join(ROOT, "scenarios")
FIXED = ["euler", "semi-implicit-euler", "symplectic-euler", "rk4", "implicit-midpoint", "implicit-midpoint/simplified",
         "variational"]
CVODE = ["cvode-adams", "cvode-bdf", "cvode-bdf/dq"]
# A method name with a variant: the settings it changes (the defaults are the analytic Jacobian and,
# for the implicit midpoint rule, full Newton)
VARIANTS = {"cvode-bdf/dq": ("cvode-bdf", {"jacobian": "dq"}),
            "implicit-midpoint/simplified": ("implicit-midpoint", {"newton": "simplified"})}
LABELS = {"cvode-bdf": "cvode-bdf (analytic J)", "cvode-bdf/dq": "cvode-bdf (DQ J)",
          "implicit-midpoint": "implicit-midpoint (full Newton)",
          "implicit-midpoint/simplified": "implicit-midpoint (simplified Newton)"}


def split(spec):
    """'cvode-bdf/dq' -> ('cvode-bdf', {'jacobian': 'dq'}); a plain method name -> (name, {})"""
    return VARIANTS.get(spec, (spec, {}))


def label(spec):
    return LABELS.get(spec, spec)

try:
    if os.environ.get("SOADYN_RUNS_CLI"):
        raise ImportError("SOADYN_RUNS_CLI is set")
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))
    import soadyn
except ImportError:
    soadyn = None
_scenes = {}


def energy_summary(r, t, E, T, W):
    """the energy-balance error (E(t) - E(0) - W(t)) / max(|E0|, peak T), W the inputs' work"""
    r["t"] = t
    scale = max(abs(E[0]), T.max(), 1e-300)
    with np.errstate(invalid="ignore", divide="ignore"):
        r["E_rel"] = (E - E[0] - W) / scale
    r["balance_error"] = float(np.abs(r["E_rel"]).max())
    r["balance_final"] = float(r["E_rel"][-1])
    return r


def run_in_process(scenario, method, t_end=None, rtol=None, dt=None, output_dt=None):
    """the same run as `soadyn run`, by soadyn.simulate (the GIL is released while it integrates)"""
    if scenario not in _scenes:
        _scenes[scenario] = soadyn.load_scenario(os.path.join(SCENARIOS, scenario + ".yaml"))
    name, options = split(method)
    tr = soadyn.simulate(_scenes[scenario], name, rtol=rtol, atol=None if rtol is None else rtol * 1e-2, dt=dt,
                         t_end=t_end, output_dt=output_dt, **options)
    s = tr.summary
    r = {"scenario": scenario, "method": method, "rtol": rtol, "dt": dt, "ok": s.completed, "status": s.status,
         "cpu": s.cpu_seconds, "rhs": s.rhs_evals, "steps": s.steps, "t_reached": s.t_reached,
         "q": tr.q[-1], "qd": tr.v[-1]}
    return energy_summary(r, tr.t, tr.total_energy, tr.kinetic_energy, tr.work_inputs)


def run(scenario, method, t_end=None, rtol=None, dt=None, output_dt=None, timeout=900):
    """One run; returns a dict with the final state, energy-balance errors, CPU time, status."""
    if soadyn is not None:
        return run_in_process(scenario, method, t_end, rtol, dt, output_dt)
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "run.h5")
        name, options = split(method)
        cmd = [SOADYN, "run", os.path.join(SCENARIOS, scenario + ".yaml"), "--method", name, "-q", "-o", out]
        for k, v in options.items():
            cmd += [f"--{k}", v]
        if rtol is not None:
            cmd += ["--rtol", repr(rtol), "--atol", repr(rtol * 1e-2)]
        if dt is not None:
            cmd += ["--dt", repr(dt)]
        if t_end is not None:
            cmd += ["--t-end", repr(t_end)]
        if output_dt is not None:
            cmd += ["--output-dt", repr(output_dt)]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return {"scenario": scenario, "method": method, "rtol": rtol, "dt": dt, "ok": False,
                    "status": f"timeout after {timeout} s", "cpu": float("nan")}
        r = {"scenario": scenario, "method": method, "rtol": rtol, "dt": dt, "ok": p.returncode == 0}
        if p.returncode not in (0, 3):
            raise RuntimeError(f"{' '.join(cmd)}: {p.stderr}")
        with h5py.File(out, "r") as f:
            s = f["solver"]  # run-time values are scalar datasets (SWMR file)
            r["status"] = s["status"][()].decode()
            r["cpu"] = float(s["cpu_seconds"][()])
            r["rhs"] = int(s["rhs_evals"][()])
            r["steps"] = int(s["steps"][()])
            r["t_reached"] = float(s["t_reached"][()])
            t, E, T = f["time"][:], f["energy/total"][:], f["energy/kinetic"][:]
            W = f["energy/work_inputs"][:] if "energy/work_inputs" in f else np.zeros_like(E)
            r["q"], r["qd"] = f["q"][-1], f["qd"][-1]
        return energy_summary(r, t, E, T, W)


_refusals = {}


def refuses(scenario, method):
    """why `method` refuses the scene's model before running (symplectic-euler: free and ball
    joints), or None"""
    key = (scenario, method)
    if key not in _refusals:
        try:
            run(scenario, method, t_end=1e-3, dt=1e-3, output_dt=1e-3)
            _refusals[key] = None
        except Exception as e:  # soadyn.Error in process, RuntimeError from the executable
            if "free or ball joint" not in str(e):
                raise
            _refusals[key] = str(e)
    return _refusals[key]


def run_many(jobs, workers=2):
    with ThreadPoolExecutor(workers) as ex:
        return list(ex.map(lambda kw: run(**kw), jobs))
