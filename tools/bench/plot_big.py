#!/usr/bin/python3
"""How long tools/plot.py takes, and how much memory, on a run of 10^7 rows (not a test).

    tools/bench/plot_big.py [--rows 10000000] [--groups state,energy] [--file big.h5] [--keep]

Writes a synthetic run file in soadyn's layout (layout_version 3: /samples with column_names and
column_units, /model's names, /solver's settings), as a 10^5 s run of the satellite (a free bus,
two hinged arrays) logged every 0.01 s with the lean groups `--log state,energy` would give, then
runs tools/plot.py on it in a fresh process and reports its wall time and peak RSS (getrusage of
the child).  The signals are smooth motions with a slow drift and a little noise, so the min/max
envelope is not trivially flat.  write_run() is also used by the tests to make files of any length.
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
import zlib

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

JOINTS = [("bus", "free"), ("left", "revolute"), ("right", "revolute")]
BODIES = ["bus", "left", "right"]


def columns(groups):
    """(name, unit) of every column of /samples for the satellite and the chosen groups"""
    q = [("q.bus." + c, "m") for c in "xyz"] + [("q.bus." + c, "1") for c in ("qw", "qx", "qy", "qz")]
    q += [("q.left", "rad"), ("q.right", "rad")]
    v = [("bus.w" + c, "rad/s") for c in "xyz"] + [("bus.v" + c, "m/s") for c in "xyz"] + [("left", "rad/s"), ("right", "rad/s")]
    cols = [("time", "s")]
    if "state" in groups:
        cols += q + [("qd." + n, u) for n, u in v] + [("qdd." + n, u + "^2" if u == "rad/s" else "m/s^2") for n, u in v]
    if "energy" in groups:
        cols += [("energy." + e, "J") for e in ("kinetic", "potential", "total", "work_inputs", "dissipated")]
    if "momentum" in groups:
        cols += [(f"momentum.linear.{c}", "kg m/s") for c in "xyz"] + [(f"momentum.angular.{c}", "kg m^2/s") for c in "xyz"]
    if "bodies" in groups:
        for kind, parts in (("position", "xyz"), ("orientation", "wxyz"), ("com", "xyz")):
            cols += [(f"bodies.{kind}.{b}.{c}", "1" if kind == "orientation" else "m") for b in BODIES for c in parts]
    return [c[0] for c in cols], [c[1] for c in cols]


def block(names, t, rng):
    """synthetic values of every column at times t"""
    out = np.empty((len(t), len(names)))
    for k, n in enumerate(names):
        if n == "time":
            out[:, k] = t
            continue
        h = (zlib.crc32(n.encode()) % 1000) / 1000.0
        out[:, k] = np.sin(0.7 * t * (1 + h)) + 1e-5 * t * h + 1e-3 * rng.standard_normal(len(t))
    # a unit quaternion turning about a slowly moving axis
    qi = [names.index(f"q.bus.q{c}") for c in "wxyz"] if "q.bus.qw" in names else []
    if qi:
        a = 0.3 * t
        axis = np.stack([np.cos(1e-3 * t), np.sin(1e-3 * t), 0.5 + 0 * t])
        axis /= np.linalg.norm(axis, axis=0)
        out[:, qi[0]] = np.cos(a / 2)
        for j in range(3):
            out[:, qi[1 + j]] = np.sin(a / 2) * axis[j]
    if "energy.total" in names:
        i = {n: names.index("energy." + n) for n in ("kinetic", "potential", "total", "work_inputs", "dissipated")}
        out[:, i["kinetic"]] = 2 + np.sin(t) ** 2
        out[:, i["potential"]] = 1 - np.sin(t) ** 2
        out[:, i["work_inputs"]] = -1e-3 * np.sqrt(t)
        out[:, i["dissipated"]] = 1e-3 * np.sqrt(t)
        out[:, i["total"]] = 3 + out[:, i["work_inputs"]] + 1e-11 * np.sqrt(t) * rng.standard_normal(len(t))
    return out


def write_run(path, rows, groups=("state", "energy"), dt=0.01, block_rows=1 << 18, seed=0):
    """a run file of `rows` rows in soadyn's layout (no views: readers of /samples need none)"""
    names, units = columns(groups)
    rng = np.random.default_rng(seed)
    w = len(names)
    with h5py.File(path, "w", libver="latest") as f:
        f.attrs["layout_version"] = 3
        f.attrs["soadyn_version"] = "synthetic"
        f.attrs["scenario_path"] = "tools/bench/plot_big.py"
        f.attrs["log_groups"] = ",".join(groups)
        m = f.create_group("model")
        m.attrs["joint_names"] = [j for j, _ in JOINTS]
        m.attrs["joint_types"] = [t for _, t in JOINTS]
        m.attrs["body_names"] = BODIES
        m.attrs["nq"], m.attrs["nv"] = 9, 8
        s = f.create_group("solver")
        s.attrs["method"] = "synthetic"
        s.create_dataset("status", data="completed")
        d = f.create_dataset("samples", (rows, w), dtype="f8", maxshape=(None, w), chunks=(max(1, 8192 // w), w))
        d.attrs["column_names"] = names
        d.attrs["column_units"] = units
        for r0 in range(0, rows, block_rows):
            n = min(block_rows, rows - r0)
            d[r0:r0 + n] = block(names, dt * np.arange(r0, r0 + n), rng)
    return names, units


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--groups", default="state,energy", help="the groups logged (state,energy,momentum,bodies)")
    ap.add_argument("--file", help="the run file (default: a temporary one); reused if it exists")
    ap.add_argument("--keep", action="store_true", help="keep the temporary file")
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="plot_big_")
    path = args.file or os.path.join(tmp, "big.h5")
    if not os.path.exists(path):
        t0 = time.perf_counter()
        write_run(path, args.rows, args.groups.split(","))
        print(f"wrote {path}: {os.path.getsize(path) / 1e9:.2f} GB in {time.perf_counter() - t0:.1f} s")
    with h5py.File(path, "r") as f:
        rows, width = f["samples"].shape
    # the file's pages are read once first, so the timing is the plot's, not the disk's
    subprocess.run(["cat", path], stdout=subprocess.DEVNULL, check=True)
    png = os.path.join(tmp, "big.png")
    usage0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu0 = usage0.ru_utime + usage0.ru_stime
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "plot.py"), path, "-o", png],
                       env=dict(os.environ, MPLBACKEND="Agg"))
    wall = time.perf_counter() - t0
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    peak = usage.ru_maxrss / 1024  # KiB → MiB (the largest child)
    cpu = usage.ru_utime + usage.ru_stime - cpu0
    if p.returncode:
        sys.exit(f"plot.py failed with status {p.returncode}")
    print(f"plot.py on {rows} rows x {width} columns ({rows * width * 8 / 1e9:.2f} GB of samples): "
          f"{wall:.2f} s wall, {cpu:.2f} s CPU, peak RSS {peak:.0f} MiB (load average {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores) -> {png}")
    if not args.keep and not args.file:
        os.remove(path)


if __name__ == "__main__":
    main()
