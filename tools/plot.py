#!/usr/bin/python3
"""Plot a soadyn run: joint trajectories, energy error against time, and momentum for free-floating
models (nq != nv).  PNG by default; --show opens a window.

    tools/plot.py out/run.h5 [-o fig.png] [--show] [--data curves.csv]
"""
import argparse
import csv
import sys

import h5py
import matplotlib
import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="HDF5 file written by soadyn run")
    ap.add_argument("-o", "--output", help="PNG to write (default: the run's name with .png)")
    ap.add_argument("--show", action="store_true", help="open a window instead of writing a PNG")
    ap.add_argument("--data", help="also write every curve drawn to this CSV (one column per curve, time first)")
    args = ap.parse_args()
    if not args.show:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    try:
        f = h5py.File(args.run, "r")
    except (OSError, RuntimeError) as e:
        try:  # a running or killed run's file: SWMR-read mode (README, "The HDF5 file")
            f = h5py.File(args.run, "r", swmr=True)
        except (OSError, RuntimeError):
            sys.exit(f"plot.py: error: {args.run}: cannot open as HDF5 ({e})")
    with f:
        t = f["time"][:]
        q, qd = f["q"][:], f["qd"][:]
        model = f["model"]  # joint names: str attributes (layout 3), a dataset before
        raw = model.attrs["joint_names"] if "joint_names" in model.attrs else model["joint_names"][:]
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in raw]
        nq, nv = int(f["model"].attrs["nq"]), int(f["model"].attrs["nv"])
        E = f["energy/total"][:]
        T = f["energy/kinetic"][:]
        lin, ang = f["momentum/linear"][:], f["momentum/angular"][:]
        solver = dict(f["solver"].attrs)
        if "status" in f["solver"]:  # a dataset since the file became SWMR; an attribute before
            solver["status"] = f["solver/status"][()]
    if len(t) == 0:
        sys.exit(f"plot.py: error: {args.run}: no samples")

    def text(v):
        return v.decode() if isinstance(v, bytes) else str(v)

    free = nq != nv
    rows = 3 if free else 2
    fig, ax = plt.subplots(rows, 1, figsize=(9, 3.0 * rows), sharex=True)
    method, status = text(solver.get("method", "?")), text(solver.get("status", "?"))
    fig.suptitle(f"{args.run}: {method}, {status}", fontsize=10)

    # joint trajectories: revolute/prismatic coordinates (a free root's position and quaternion skipped)
    curves = {"t": t}  # every curve drawn, for --data
    labels = []
    if free:
        cols = list(range(7, nq))
        labels = names[1:]
    else:
        cols = list(range(nq))
        labels = names
    for c, name in zip(cols, labels):
        ax[0].plot(t, q[:, c], label=name)
        curves[f"q {name}"] = q[:, c]
    if free:
        for k, c in enumerate("xyz"):
            ax[0].plot(t, q[:, k], "--", label=f"{names[0]}.{c}")
            curves[f"q {names[0]}.{c}"] = q[:, k]
    ax[0].set_ylabel("q [rad or m]")
    ax[0].legend(fontsize=8, ncol=4)
    ax[0].grid(alpha=0.3)

    scale = max(abs(E[0]), T.max(), 1e-300)
    curves["energy error"] = np.maximum(np.abs(E - E[0]) / scale, 1e-17)
    ax[1].semilogy(t, curves["energy error"])
    ax[1].set_ylabel("|E(t) - E(0)| / max(|E0|, max T)")
    ax[1].grid(alpha=0.3, which="both")

    if free:
        for k, c in enumerate("xyz"):
            curves[f"angular momentum change {c}"] = np.maximum(np.abs(ang[:, k] - ang[0, k]), 1e-17)
            curves[f"linear momentum change {c}"] = np.maximum(np.abs(lin[:, k] - lin[0, k]), 1e-17)
            ax[2].semilogy(t, curves[f"angular momentum change {c}"], label=f"angular {c}")
            ax[2].semilogy(t, curves[f"linear momentum change {c}"], "--", label=f"linear {c}")
        ax[2].set_ylabel("momentum change")
        ax[2].legend(fontsize=8, ncol=3)
        ax[2].grid(alpha=0.3, which="both")
    ax[-1].set_xlabel("t [s]")
    fig.tight_layout()
    if args.data:
        with open(args.data, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(curves)
            w.writerows(zip(*(map(repr, map(float, c)) for c in curves.values())))
    if args.show:
        plt.show()
    else:
        out = args.output or args.run.rsplit(".", 1)[0] + ".png"
        fig.savefig(out, dpi=90)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
