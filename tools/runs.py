"""Shared by tools/work_precision.py and tools/stability.py: run `soadyn run` and read its file."""
import os
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
SCENARIOS = os.path.join(ROOT, "scenarios")
FIXED = ["euler", "symplectic-euler", "rk4", "implicit-midpoint"]
CVODE = ["cvode-adams", "cvode-bdf"]


def run(scenario, method, t_end=None, rtol=None, dt=None, output_dt=None, timeout=900):
    """One run; returns a dict with the final state, energy errors, CPU time, status."""
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "run.h5")
        cmd = [SOADYN, "run", os.path.join(SCENARIOS, scenario + ".yaml"), "--method", method, "-q", "-o", out]
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
            r["q"], r["qd"] = f["q"][-1], f["qd"][-1]
            r["t"] = t
            scale = max(abs(E[0]), T.max(), 1e-300)
            with np.errstate(invalid="ignore", divide="ignore"):
                r["E_rel"] = (E - E[0]) / scale
            r["energy_error"] = float(np.abs(r["E_rel"]).max())
            r["energy_final"] = float(r["E_rel"][-1])
        return r


def run_many(jobs, workers=2):
    with ThreadPoolExecutor(workers) as ex:
        return list(ex.map(lambda kw: run(**kw), jobs))
