#!/usr/bin/python3
"""Kill `soadyn run` with SIGKILL at random moments and check every file it leaves.

Trials cycle through four phases, timed by calibration runs: file creation, the first flush (when
the file is put in place), mid-run and the finish.  Half of them start with an older run's file at
the output path.  After each kill the path must hold either that older file byte for byte (the run
had not yet put its file in place), no file (there was none), or a file that opens (plainly, or
with HDF5's SWMR-read flag as README says), reads whole, has series of one length, increasing time,
the scenario's text, a status of "running" or "completed", and rows equal bit for bit to the same
run's uninterrupted rows.

    tools/kill_loop.py [--trials 500] [--seed 1] [--soadyn build/soadyn]
"""
import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SERIES = ["time", "q", "qd", "qdd", "energy/kinetic", "energy/potential", "energy/total", "momentum/linear",
          "momentum/angular", "samples"]
PHASES = ["creation", "first flush", "mid-run", "finish"]


def open_run_file(path):
    """h5py.File for a soadyn run file: plainly, else in SWMR-read mode (a running or killed run)."""
    try:
        return h5py.File(path, "r")
    except (OSError, RuntimeError):
        return h5py.File(path, "r", swmr=True)


def check_file(path, scenario_text, complete_rows=None, reference=None):
    """Problems with a run file, as a list of strings (empty: the file is whole).  `reference`: the
    /samples of the same run uninterrupted, which the file's rows must equal bit for bit."""
    try:
        f = open_run_file(path)
    except Exception as e:  # OSError, or RuntimeError from a damaged header
        return [f"does not open: {type(e).__name__}: {e}"]
    problems = []
    with f:
        try:
            data = {}
            f.visititems(lambda name, obj: data.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
            lengths = {s: len(data[s]) for s in SERIES}
            if len(set(lengths.values())) != 1:
                problems.append(f"series lengths differ: {lengths}")
            t = data["time"]
            if len(t) < 1:
                problems.append("no rows")
            if np.any(np.diff(t) <= 0):
                problems.append("time does not increase")
            if not np.all(np.isfinite(data["samples"])):
                problems.append("non-finite values")
            n = len(data["samples"])
            if reference is not None and (n > len(reference) or not np.array_equal(data["samples"], reference[:n])):
                problems.append("rows differ from the same run's uninterrupted rows")
            if data["scenario"].decode() != scenario_text:
                problems.append("/scenario differs from the scenario file")
            status = data["solver/status"].decode()
            if status not in ("running", "completed"):
                problems.append(f"status {status!r}")
            if status == "completed" and complete_rows is not None and len(t) != complete_rows:
                problems.append(f"completed with {len(t)} rows, expected {complete_rows}")
        except Exception as e:  # a read error is what this loop looks for
            problems.append(f"does not read whole: {type(e).__name__}: {e}")
    return problems


def same_bytes(path, data):
    with open(path, "rb") as f:
        return f.read() == data


def calibrate(cmd, work, runs=3):
    """Median times after the start at which the temporary file appears, the file is put in place
    (its first flush) and the run ends."""
    out = os.path.join(work, "calibrate.h5")
    marks = []
    for _ in range(runs):
        if os.path.exists(out):
            os.remove(out)
        t0 = time.monotonic()
        p = subprocess.Popen(cmd + ["-o", out])
        created = published = None
        while p.poll() is None:
            now = time.monotonic() - t0
            if created is None and any(n.startswith("calibrate.h5.") and n.endswith(".tmp") for n in os.listdir(work)):
                created = now
            if published is None and os.path.exists(out):
                published = now
            time.sleep(0.001)
        end = time.monotonic() - t0
        marks.append((created or 0.0, published or end, end))
    os.remove(out)
    return [sorted(m[i] for m in marks)[runs // 2] for i in range(3)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=500)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--soadyn", default=os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn")))
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    scenario = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
    with open(scenario) as f:
        text = f.read()
    # rk4 at a small step: about a second of work; many rows and a flush every 10 ms, so that
    # kills land in flushes often
    cmd = [args.soadyn, "run", scenario, "--method", "rk4", "--dt", "2e-5", "--t-end", "1.5", "--output-dt", "0.001",
           "--flush-interval", "0.01", "-q"]
    rows = 1501
    work = tempfile.mkdtemp(prefix="soadyn_kill_")
    try:
        old = os.path.join(work, "old.h5")
        subprocess.run(cmd + ["-o", old], check=True)
        with open(old, "rb") as f:
            old_bytes = f.read()
        with h5py.File(old, "r") as f:
            reference = f["samples"][()]
        created, published, duration = calibrate(cmd, work)
        print(f"calibration: temporary file after {created * 1e3:.0f} ms, in place after {published * 1e3:.0f} ms, "
              f"run over after {duration * 1e3:.0f} ms")
        bad, litter, counts, outcomes = [], 0, {p: 0 for p in PHASES}, {}
        for k in range(args.trials):
            phase = PHASES[k % 4]
            delay = {"creation": lambda: rng.uniform(0.5 * created, published),
                     "first flush": lambda: rng.uniform(published - 0.2 * (published - created), published + 0.05),
                     "mid-run": lambda: rng.uniform(published, 0.9 * duration),
                     "finish": lambda: rng.uniform(0.8, 1.6) * duration}[phase]()
            out = os.path.join(work, f"run{k}.h5")
            had_old = rng.random() < 0.5
            if had_old:
                shutil.copyfile(old, out)
            p = subprocess.Popen(cmd + ["-o", out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(delay)
            p.send_signal(signal.SIGKILL)
            rc = p.wait()
            counts[phase] += 1
            if rc not in (0, -signal.SIGKILL):
                bad.append((k, phase, delay, [f"exit status {rc}"]))
                continue
            if not os.path.exists(out):
                problems = ["an older file was lost"] if had_old else []
                outcome = "not yet in place"
            elif had_old and same_bytes(out, old_bytes):
                problems = []
                outcome = "not yet in place"
            else:
                problems = check_file(out, text, rows, reference)
                try:
                    h5py.File(out, "r").close()
                    outcome = "closed (opens plainly)"
                except Exception:
                    outcome = "in progress (opens with swmr=True)" if not problems else "unreadable"
            outcomes[outcome] = outcomes.get(outcome, 0) + 1
            if rc == 0 and not problems and check_file(out, text, rows) == [] and \
                    h5py.File(out, "r")["solver/status"][()] != b"completed":
                problems = ["exit 0 without status completed"]
            if problems:
                bad.append((k, phase, delay, problems))
            if args.verbose:
                print(f"{k:4d} {phase:12s} {delay * 1e3:7.1f} ms rc {rc:3d} {'; '.join(problems) or 'ok'}")
            for name in os.listdir(work):  # a killed run leaves its temporary file and lock file
                if name.startswith(f"run{k}.h5."):
                    litter += 1
                    os.remove(os.path.join(work, name))
            if os.path.exists(out):
                os.remove(out)
        print(f"kill loop: {len(bad)} unreadable or wrong / {args.trials} trials "
              f"({', '.join(f'{n} {p}' for p, n in counts.items())}); run length {duration:.2f} s; "
              f"{litter} temporary or lock files left by killed runs (removed)")
        print("files left: " + ", ".join(f"{n} {o}" for o, n in sorted(outcomes.items())))
        for k, phase, delay, problems in bad:
            print(f"  trial {k} ({phase}, killed after {delay * 1e3:.1f} ms): {'; '.join(problems)}")
        return 1 if bad else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
