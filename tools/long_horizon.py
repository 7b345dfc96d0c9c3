#!/usr/bin/python3
"""The satellite over 1000 s (issue 61's table): for each method, the CPU time of the run, the largest
|E(t) - E(0)| / |E(0)| and the largest |L(t) - L(0)| / |L(0)| (angular momentum about the inertial
origin, the vector's change over its norm), each run by `soadyn run` (build/soadyn) and read back
from its file.  Writes tools/results/long_horizon.md (a Markdown table) and prints it.

    tools/long_horizon.py [--t-end 1000] [--scene satellite_two_arrays] [--out tools/results/long_horizon.md]
"""
import argparse
import os
import re
import subprocess
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))

# (label, method, its options)
RUNS = [
    ("cvode-adams, rtol 1e-10", "cvode-adams", ["--rtol", "1e-10", "--atol", "1e-12"]),
    ("rk4, dt 0.1", "rk4", ["--dt", "0.1"]),
    ("implicit-midpoint, dt 0.1", "implicit-midpoint", ["--dt", "0.1"]),
    ("semi-implicit-euler, dt 0.01", "semi-implicit-euler", ["--dt", "0.01"]),
    ("variational, dt 0.1", "variational", ["--dt", "0.1"]),
    ("variational, dt 0.01", "variational", ["--dt", "0.01"]),
]


def run(scene, method, options, t_end):
    """(CPU s, max |ΔE|/|E0|, max |ΔL|/|L0|, the run's status line)"""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run.h5")
        cmd = [SOADYN, "run", os.path.join(ROOT, "scenarios", scene + ".yaml"), "-o", out, "--method", method,
               "--t-end", str(t_end), "--output-dt", "1", "--log", "energy,momentum"] + options
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            return None, None, None, (p.stderr or p.stdout).strip().splitlines()[-1]
        cpu = float(re.search(r"CPU time\s+([0-9.eE+-]+)", p.stdout).group(1))
        status = re.search(r"status\s+(.*)", p.stdout).group(1)
        with h5py.File(out, "r") as f:
            E = np.asarray(f["/energy/total"][...]).ravel()
            L = np.asarray(f["/momentum/angular"][...]).reshape(-1, 3)
    dE = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    dL = float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]))
    return cpu, dE, dL, status


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=1000.0)
    ap.add_argument("--scene", default="satellite_two_arrays")
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "results", "long_horizon.md"))
    a = ap.parse_args()
    lines = [f"`{a.scene}` over {a.t_end:g} s (`tools/long_horizon.py`; CPU of one run on a shared 2-core machine)",
             "", "| method | CPU | max abs ΔE / E | max abs ΔL / L |", "|---|---|---|---|"]
    for label, method, options in RUNS:
        cpu, dE, dL, status = run(a.scene, method, options, a.t_end)
        if cpu is None:
            lines.append(f"| {label} | — | {status} | |")
        else:
            lines.append(f"| {label} | {cpu * 1e3:.3g} ms | {dE:.2g} | {dL:.2g} |")
        print(lines[-1], flush=True)
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
