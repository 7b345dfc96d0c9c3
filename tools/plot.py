#!/usr/bin/python3
"""Plot a soadyn run: joint coordinates by unit, the orientation of free and ball joints, the
controllers' torques and forces, the torques holding prescribed joints' motion, the closed loops' forces and closure, the energy-balance error on a log axis and, for a free-floating
model, the change of momentum; the joint limits' events (/events) as dashed lines on every panel.

    tools/plot.py RUN.h5 [-o fig.png|.svg|.pdf] [--joints a,b] [--bins N] [--show] [--data curves.csv]
                  [--compare OTHER.h5,...]

Every axis carries the unit the file gives its columns (/samples' column_units).  A free or ball
joint's orientation is drawn as its rotation vector θ·u (the quaternion taken with q_w ≥ 0, so
|θ| ≤ π).  /samples is read in blocks and reduced, per pixel column of the plot (--bins, by
default the axes' width in pixels), to the minimum and maximum of each curve, so any length of
run plots in bounded time and memory and narrow spikes stay visible; a run with fewer rows than
twice the bins is drawn point by point.  A running or killed run's file is read in SWMR mode.
--compare: other runs of the same joints (a fitted scene's run against the logged one, soadyn
identify) drawn dashed over the joint panels in the same colours, and per run a log panel of
max_j |q_j − q_j(RUN)| at RUN's sample times (the other run's q linearly interpolated there).
"""
import argparse
import csv
import os
import stat
import sys

import h5py
import matplotlib
import numpy as np

QUAT = ("qw", "qx", "qy", "qz")
BLOCK = 1 << 16  # rows read at a time
FLOOR = 1e-17  # log panels draw an exact zero here


def fail(message):
    print(f"plot.py: error: {message}", file=sys.stderr)
    sys.exit(2)


def text(v):
    if isinstance(v, np.ndarray):
        v = v[()]
    return v.decode() if isinstance(v, bytes) else str(v)


KINDS = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
         (stat.S_ISSOCK, "a socket"))


def open_run(path):
    # a regular file only, with the reason otherwise, as soadyn's readers say it (HDF5 would wait
    # for ever on a FIFO)
    try:
        mode = os.stat(path).st_mode
    except OSError as e:
        fail(f"{path}: cannot open the file ({e.strerror[:1].lower() + e.strerror[1:]})")
    if stat.S_ISDIR(mode):
        fail(f"{path}: is a directory, expected a run file (HDF5, from soadyn run)")
    if not stat.S_ISREG(mode):
        kind = next((k for test, k in KINDS if test(mode)), "not a regular file")
        fail(f"{path}: not a regular file ({kind}), expected a run file (HDF5, from soadyn run)")
    try:  # a running or killed run's file opens only in SWMR-read mode
        return h5py.File(path, "r", swmr=True)
    except (OSError, RuntimeError, ValueError):
        try:
            return h5py.File(path, "r")
        except (OSError, RuntimeError) as e:
            fail(f"{path}: cannot open as HDF5 ({e})")


def joints_of(names, model):
    """{joint: [(part, column index)]} in file order, from the q.* columns; part '' for 1-DOF"""
    known = [text(j) for j in model.attrs.get("joint_names", [])] if model is not None else []
    joints = {}
    for k, n in enumerate(names):
        if not n.startswith("q."):
            continue
        rest = n[2:]
        joint = next((j for j in sorted(known, key=len, reverse=True) if rest == j or rest.startswith(j + ".")), None)
        if joint is None:  # no joint list: a known suffix (x, y, z, qw…, theta) marks a component
            joint = rest.rsplit(".", 1)[0] if "." in rest and rest.rsplit(".", 1)[1] in QUAT + ("x", "y", "z", "theta") else rest
        joints.setdefault(joint, []).append((rest[len(joint) + 1:], k))
    return joints


class Curve:
    """one drawn line: its label and how its values come from a block of /samples' rows"""

    def __init__(self, label, f, post=None):
        self.label, self.f, self.post = label, f, post  # post: applied to the reduced values (monotone)


def column(k):
    return lambda b, ctx: b[:, k]


def rotation_vector(cols, axis):
    """component `axis` of θ·u for the quaternion in columns cols (w, x, y, z)"""
    def f(b, ctx):
        key = ("rotvec", tuple(cols))
        if ctx.get("block") is not b:  # one block's rotation vectors, computed once for its 3 curves
            ctx["block"], ctx["memo"] = b, {}
        if key not in ctx["memo"]:
            ctx["memo"][key] = rotvec(b[:, cols])
        return ctx["memo"][key][:, axis]
    return f


def rotvec(q):
    """θ·u of quaternions q (rows w, x, y, z): θ = 2 atan2(|v|, w), u = v / |v|"""
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)  # the same rotation with q_w ≥ 0: θ in [0, π]
    s = np.linalg.norm(q[:, 1:], axis=1)
    theta = 2 * np.arctan2(s, q[:, 0])
    with np.errstate(invalid="ignore", divide="ignore"):  # θ/|v| → 2/w as |v| → 0
        scale = np.where(s > 1e-12, theta / np.where(s > 0, s, 1), 2.0 / np.maximum(q[:, 0], 1e-300))
    return scale[:, None] * q[:, 1:]


def plan(names, units, model, chosen):
    """the panels: (y label, [Curve], log scale?)"""
    idx = {n: k for k, n in enumerate(names)}
    joints = joints_of(names, model)
    if chosen:
        unknown = [j for j in chosen if j not in joints]
        if unknown:
            fail(f"--joints: no joint named {', '.join(map(repr, unknown))} in the file "
                 f"(its joints: {', '.join(joints) or 'none: the run logged no state'})")
        joints = {j: joints[j] for j in chosen}
    panels = []
    by_unit = {}
    rotations = []
    for j, parts in joints.items():
        quat = {p: k for p, k in parts if p in QUAT}
        if len(quat) == 4:
            rotations += [Curve(f"rotvec.{j}.{'xyz'[a]}", rotation_vector([quat[p] for p in QUAT], a)) for a in range(3)]
        for p, k in parts:
            if p not in QUAT:
                by_unit.setdefault(units[k], []).append(Curve(f"q.{j}.{p}" if p else f"q.{j}", column(k)))
    what = {"rad": "joint angle", "m": "joint position"}
    for u, curves in by_unit.items():
        panels.append((f"{what.get(u, 'q')} [{u}]", curves, False))
    if rotations:
        rad = next((units[k] for j in joints for p, k in joints[j] if p == "" and units[k] == "rad"), "rad")
        panels.append((f"orientation: rotation vector θ·u [{rad}]\n(free/ball joints, quaternion with q_w ≥ 0)",
                       rotations, False))

    # the controllers' output, one panel per unit (N m for revolute DOFs, N for prismatic ones)
    by_unit = {}
    for k, n in enumerate(names):
        if n.startswith("control."):
            by_unit.setdefault(units[k], []).append(Curve(n, column(k)))
    for u, curves in by_unit.items():
        panels.append((f"control {'force' if u == 'N' else 'torque'} [{u}]", curves, False))
    # the torques (forces) holding the prescribed joints' motion (/prescribed), one panel per unit
    held = {}
    for k, n in enumerate(names):
        if n.startswith("prescribed."):
            held.setdefault(units[k], []).append(Curve(n[len("prescribed."):], column(k)))
    for u, curves in held.items():
        panels.append((f"prescribed joints' {'force' if u == 'N' else 'torque'} [{u}]", curves, False))
    # the closed loops' forces λ (/loops/force), one panel per unit, and their closure |φ| (log axis)
    forces = {}
    for k, n in enumerate(names):
        if n.startswith("loops.force."):
            forces.setdefault(units[k], []).append(Curve(n[len("loops.force."):], column(k)))
    for u, curves in forces.items():
        panels.append((f"loop {'forces' if u == 'N' else 'torques'} λ [{u}]", curves, False))
    if "loops.closure" in idx:
        k = idx["loops.closure"]
        panels.append((f"loop closure |φ| [{units[k]}]",
                       [Curve("closure", lambda b, ctx, k=k: np.maximum(np.abs(b[:, k]), FLOOR))], True))

    if "energy.total" in idx and "energy.kinetic" in idx:
        w, loss = idx.get("energy.work_inputs"), idx.get("energy.impact_loss")
        wp = idx.get("energy.work_prescribed")
        # E − E0, less the work W of the inputs when logged (and W_p, the prescribed joints'), plus
        # the energy L the joint limits' impacts took when logged: (column, sign) of each term, from
        # the first row
        terms = [(idx["energy.total"], 1.0)] + ([(w, -1.0)] if w is not None else []) + \
            ([(wp, -1.0)] if w is not None and wp is not None else []) + \
            ([(loss, 1.0)] if w is not None and loss is not None else [])
        f = lambda b, ctx: np.abs(sum(s * (b[:, k] - ctx["row0"][k]) for k, s in terms))  # noqa: E731
        if w is None:
            label = "energy error (no work logged)\n|E − E0| / max(|E0|, max T) [1]"
        else:
            label = (f"energy-balance error\n|E − E0 − W{' − W_p' if wp is not None else ''}"
                     f"{' + L' if loss is not None else ''}| / max(|E0|, max T) [1]")
        # the scale needs the whole run's peak kinetic energy: applied after the reduction
        panels.append((label, [Curve("energy error", f, lambda y, ctx: np.maximum(y / ctx["scale"], FLOOR))], True))

    free = any(len([p for p, _ in parts if p in QUAT + ("x", "y", "z")]) == 7 for parts in joints_of(names, model).values())
    if free:
        for kind in ("linear", "angular"):
            ks = [idx.get(f"momentum.{kind}.{c}") for c in "xyz"]
            if None in ks:
                continue
            curves = [Curve(f"{kind} momentum change {c}",
                            lambda b, ctx, k=k: np.maximum(np.abs(b[:, k] - ctx["row0"][k]), FLOOR)) for c, k in zip("xyz", ks)]
            panels.append((f"|{kind} momentum − initial| [{units[ks[0]]}]", curves, True))
    return panels


def reduce(d, t_col, curves, bins, rows):
    """x and y of every curve as drawn: all rows when few, else per time bin its min and max"""
    buf = np.empty((min(rows, BLOCK), d.shape[1]))

    def read(r0, r1):  # into one reused buffer (h5py's slicing allocates and is ~8x slower here)
        d.read_direct(buf, np.s_[r0:r1], np.s_[0:r1 - r0])
        return buf[:r1 - r0]

    first = read(0, 1)[0].copy()
    t0, t1 = first[t_col], read(rows - 1, rows)[0][t_col]
    ctx = {"row0": first}
    names = d.attrs["column_names"]
    k_E = next((k for k, n in enumerate(names) if text(n) == "energy.total"), None)
    k_T = next((k for k, n in enumerate(names) if text(n) == "energy.kinetic"), None)
    ctx["E0"] = first[k_E] if k_E is not None else 0.0
    peak_T = 0.0  # for the energy error's scale max(|E0|, max T)

    def finish(x, y):
        ctx["scale"] = max(abs(ctx["E0"]), peak_T, 1e-300)
        for k, c in enumerate(curves):
            if c.post:
                y[:, k] = c.post(y[:, k], ctx)
        return x, y

    def values(b):
        nonlocal peak_T
        if k_T is not None:
            peak_T = max(peak_T, float(np.nanmax(np.r_[b[:, k_T], 0.0])))
        v = np.empty((len(b), len(curves)), order="F")  # column by column
        with np.errstate(invalid="ignore", over="ignore"):
            for k, c in enumerate(curves):
                v[:, k] = c.f(b, ctx)
        return v

    if rows <= 2 * bins or not (t1 > t0):  # few rows: every one drawn
        b = read(0, rows)
        v = values(b)
        v[~np.isfinite(v)] = np.nan
        return finish(b[:, t_col].copy(), v)
    lo = np.full((bins, len(curves)), np.nan)
    hi = np.full((bins, len(curves)), np.nan)
    for r0 in range(0, rows, BLOCK):
        b = read(r0, min(rows, r0 + BLOCK))
        v = values(b)
        which = np.clip(((b[:, t_col] - t0) / (t1 - t0) * bins).astype(np.int64), 0, bins - 1)
        # rows are in time order: each bin is one run of rows in the block
        starts = np.flatnonzero(np.r_[True, which[1:] != which[:-1]])
        ub = which[starts]
        with np.errstate(invalid="ignore"):
            lo[ub] = np.fmin(lo[ub], np.fmin.reduceat(v, starts, axis=0))
            hi[ub] = np.fmax(hi[ub], np.fmax.reduceat(v, starts, axis=0))
    lo[~np.isfinite(lo)] = np.nan  # a bin reaching ±inf (a run gone unstable) is left out
    hi[~np.isfinite(hi)] = np.nan
    centre = t0 + (np.arange(bins) + 0.5) * (t1 - t0) / bins
    x = np.repeat(centre, 2)
    y = np.empty((2 * bins, len(curves)))
    y[0::2], y[1::2] = lo, hi
    return finish(x, y)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="HDF5 file written by soadyn run")
    ap.add_argument("-o", "--output", help="figure to write: .png (default: the run's name), .svg or .pdf")
    ap.add_argument("--joints", help="comma-separated joint names to draw (default: all)")
    ap.add_argument("--bins", type=int, help="time bins (min and max of each); default: the axes' width in pixels")
    ap.add_argument("--show", action="store_true", help="open a window instead of writing a file")
    ap.add_argument("--data", help="also write every curve drawn to this CSV (x first, then one column per curve)")
    ap.add_argument("--compare", help="comma-separated runs of the same joints drawn over RUN's joint panels, with "
                                      "each one's largest |q - q(RUN)| on a log panel")
    args = ap.parse_args()
    out = args.output or os.path.splitext(args.run)[0] + ".png"
    ext = os.path.splitext(out)[1].lower()
    if not args.show and ext not in (".png", ".svg", ".pdf"):
        fail(f"-o {out}: expected a .png, .svg or .pdf file name")
    if args.bins is not None and args.bins < 1:
        fail(f"--bins {args.bins}: expected a positive number")
    if not args.show:
        matplotlib.use("Agg")
    matplotlib.rcParams["svg.fonttype"] = "none"  # SVG text stays text: smaller, searchable, editable
    import matplotlib.pyplot as plt

    with open_run(args.run) as f:
        if "samples" not in f or "column_names" not in f["samples"].attrs:
            fail(f"{args.run}: no /samples with column_names (not a run file from this soadyn; run it again)")
        d = f["samples"]
        names = [text(n) for n in d.attrs["column_names"]]
        units = [text(u) for u in d.attrs["column_units"]]
        if "time" not in names:
            fail(f"{args.run}: /samples has no time column")
        rows = d.shape[0]
        if rows == 0:
            fail(f"{args.run}: no samples yet")
        model = f["model"] if "model" in f else None
        chosen = [j for j in args.joints.split(",") if j] if args.joints else None
        panels = plan(names, units, model, chosen)
        if not panels:
            fail(f"{args.run}: nothing to plot (the run logged neither state nor energy)")
        solver = f["solver"] if "solver" in f else None
        method = text(solver.attrs.get("method", "?")) if solver is not None else "?"
        status = text(solver["status"][()]) if solver is not None and "status" in solver else "?"

        events = np.empty(0)
        if "events" in f:  # rows (t, dof, side, kind, v_before, v_after, energy_lost)
            ev = f["events"]
            if ev.ndim != 2 or ev.shape[1] < 1 or (ev.shape[0] and not np.all(np.isfinite(ev[:, 0]))):
                fail(f"{args.run}: /events: expected rows of (t, dof, side, kind, v_before, v_after, energy_lost), "
                     f"got shape {ev.shape}")
            events = ev[:, 0] if ev.shape[0] else events

        width_in, dpi = 10.0, 100
        bins = args.bins or int(0.8 * width_in * dpi)
        curves = [c for _, cs, _ in panels for c in cs]
        x, y = reduce(d, names.index("time"), curves, bins, rows)
        q_cols = [k for k, n in enumerate(names) if n.startswith("q.") and n.split(".")[-1] not in QUAT]
        t_main = d[:, names.index("time")]
        q_main = d[:, q_cols] if q_cols else np.empty((rows, 0))
    others = []  # (label, t, {column name: values})
    for path in (p for p in (args.compare or "").split(",") if p):
        with open_run(path) as g:
            if "samples" not in g or "column_names" not in g["samples"].attrs:
                fail(f"--compare {path}: no /samples with column_names (not a run file from this soadyn)")
            gn = [text(n) for n in g["samples"].attrs["column_names"]]
            missing = [names[k] for k in q_cols if names[k] not in gn]
            if missing or "time" not in gn:
                fail(f"--compare {path}: no column {(missing or ['time'])[0]} (a run of other joints?)")
            gd = g["samples"][...]
            others.append((os.path.splitext(os.path.basename(path))[0], gd[:, gn.index("time")],
                           {names[k]: gd[:, gn.index(names[k])] for k in q_cols}))
    for label, t, qs in others:  # max_j |q_j − q_j(RUN)| at RUN's times
        dev = np.max(np.abs(np.column_stack([np.interp(t_main, t, qs[names[k]]) for k in q_cols]) - q_main), axis=1) \
            if q_cols else np.zeros(rows)
        panels.append((f"max |q − q(run)|, {label}\n[{units[q_cols[0]] if q_cols else '1'}]",
                       [Curve(f"{label} − {os.path.splitext(os.path.basename(args.run))[0]}", None)], True))
        curves.append(panels[-1][1][0])
        yd = np.maximum(dev, FLOOR)
        if len(x) == rows:
            y = np.column_stack([y, yd])
        else:  # per bin, as the other curves: min and max
            which = np.clip(((t_main - t_main[0]) / (t_main[-1] - t_main[0]) * bins).astype(np.int64), 0, bins - 1)
            lo, hi = np.full(bins, np.nan), np.full(bins, np.nan)
            np.fmin.at(lo, which, yd)
            np.fmax.at(hi, which, yd)
            col_ = np.empty(2 * bins)
            col_[0::2], col_[1::2] = lo, hi
            y = np.column_stack([y, col_])

    fig, axes = plt.subplots(len(panels), 1, figsize=(width_in, 2.6 * len(panels) + 0.6), sharex=True, squeeze=False,
                             layout="constrained")
    axes = axes[:, 0]
    fig.suptitle(f"{args.run}: {method}, {status}, {rows} rows" + ("" if len(x) == rows else f" (min/max per {bins} bins)"),
                 fontsize=10)
    col = 0
    for ax, (label, cs, log) in zip(axes, panels):
        for i, c in enumerate(cs):  # past the 10 colours of the cycle, dashed then dotted
            # a log curve at the 1e-17 floor all along is an exact zero: the legend says so
            zero = log and bool(np.all(y[:, col][np.isfinite(y[:, col])] <= FLOOR))
            line, = ax.plot(x, y[:, col], label=c.label + (" (0 at every row)" if zero else ""), lw=0.8,
                            ls=("-", "--", ":")[i // 10 % 3])
            for j, (name, t, qs) in enumerate(others):  # the compared runs over this joint's curve
                if c.label in qs:
                    ax.plot(t, qs[c.label], color=line.get_color(), lw=1.2, ls=((0, (4, 3)), (0, (1, 2)))[j % 2],
                            alpha=0.8, label=f"{c.label} ({name})")
            col += 1
        if log:  # from just below the bulk of the curve, not from the floor of an exact zero at t = 0,
            ax.set_yscale("log")  # and below the floor itself when that is all there is
            vals = y[:, col - len(cs):col]
            if np.isfinite(vals).any():
                ax.set_ylim(bottom=min(max(FLOOR, 0.3 * float(np.nanpercentile(vals, 1))), 0.3 * float(np.nanmax(vals))))
        if len(events):  # dashed lines at the joint limits' events, under the curves (the y range kept)
            ylim = ax.get_ylim()
            ax.vlines(events, 0, 1, transform=ax.get_xaxis_transform(), colors="#c2255c", linestyles=(0, (3, 3)),
                      lw=0.8, alpha=0.7, zorder=0.5, gid="limit-events",
                      label=f"joint-limit events ({len(events)})" if ax is axes[0] else None)
            ax.set_ylim(ylim)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3, which="both")
        if len(cs) > 1 or (len(events) and ax is axes[0]):
            if len(cs) > 4:  # crowded: outside the axes, on the right
                ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
            else:
                ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel(f"t [{units[names.index('time')]}]")
    if args.data:
        with open(args.data, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t"] + [c.label for c in curves])
            w.writerows([repr(float(a)) for a in row] for row in np.column_stack([x, y]))
    if args.show:
        plt.show()
    else:
        fig.savefig(out, dpi=dpi)
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
