#!/usr/bin/python3
"""soadyn export: the CSV and JSON read back to the very doubles in /samples (written by soadyn run,
and by h5py with awkward values), --columns and --every choose what the file has, bad input gets
one line and exit status 2, a full disk one line and exit status 4 with nothing half-written, the
input is never touched, and a file still being written exports the rows flushed so far."""
import csv
import hashlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import h5py
import numpy as np

ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))
sys.path.insert(0, os.path.join(ROOT, "tools", "bench"))
import plot_big  # noqa: E402  (write_run: a run file in soadyn's layout, of any length)


def export(*args, timeout=120):
    return subprocess.run([SOADYN, "export", *args], capture_output=True, text=True, timeout=timeout)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], float).reshape(len(rows) - 1, len(rows[0]))


def samples(path):
    with h5py.File(path, "r", swmr=True) as f:
        d = f["samples"]
        text = lambda v: v.decode() if isinstance(v, bytes) else v  # noqa: E731 (fixed-length: bytes)
        return [text(n) for n in d.attrs["column_names"]], [text(u) for u in d.attrs["column_units"]], d[:]


def same(a, b):
    """equal as doubles, NaN where NaN (a text round trip must give back the very bits)"""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b)))) and \
        bool(np.all(np.signbit(a) == np.signbit(b)))


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


class Base(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)

    def ok(self, *args):
        p = export(*args)
        self.assertEqual(p.returncode, 0, p.stderr)
        return p

    def refused(self, *args, status=2, says=""):
        p = export(*args)
        self.assertEqual(p.returncode, status, p.stdout + p.stderr)
        lines = p.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, p.stderr)
        self.assertIn(says, lines[0])
        return lines[0]


class Synthetic(Base):
    """a file in soadyn's layout written by h5py: every column, and values text handles badly"""

    def setUp(self):
        super().setUp()
        self.run = self.path("run.h5")
        self.names, self.units = plot_big.write_run(self.run, 500, ("state", "energy", "momentum", "bodies"))
        awkward = [math.nan, math.inf, -math.inf, 5e-324, -0.0, 1.7976931348623157e308, 0.1, 1 / 3, -2.5e-310]
        with h5py.File(self.run, "r+") as f:
            d = f["samples"]
            row = d[7]
            row[1:1 + len(awkward)] = awkward
            d[7] = row

    def test_csv_round_trips_every_column(self):
        self.ok(self.run, "--csv", self.path("all.csv"))
        header, data = read_csv(self.path("all.csv"))
        self.assertEqual(header, [f"{n} [{u}]" for n, u in zip(self.names, self.units)])
        self.assertEqual(header[:2], ["time [s]", "q.bus.x [m]"])
        names, _, table = samples(self.run)
        self.assertTrue(same(data, table), "CSV values differ from /samples")
        self.assertTrue(np.isnan(data[7, 1]) and data[7, 2] == math.inf and data[7, 5] == 0 and np.signbit(data[7, 5]))
        # numpy reads it too
        arr = np.genfromtxt(self.path("all.csv"), delimiter=",", skip_header=1)
        self.assertTrue(same(arr, table))

    def test_json_round_trips(self):
        self.ok(self.run, "--json", self.path("all.json"), "--columns", "q")
        with open(self.path("all.json")) as f:
            j = json.load(f)
        names, units, table = samples(self.run)
        cols = [0] + [k for k, n in enumerate(names) if n.startswith("q.")]
        self.assertEqual(j["columns"], [names[k] for k in cols])
        self.assertEqual(j["units"], [units[k] for k in cols])
        data = np.array([[math.nan if x is None else x for x in r] for r in j["rows"]], float)
        expected = table[:, cols].copy()
        expected[~np.isfinite(expected)] = math.nan  # non-finite numbers are null in JSON
        self.assertTrue(same(data, expected))

    def test_columns_by_name_group_and_joint(self):
        cases = {
            "q.left,energy.total": ["time", "q.left", "energy.total"],
            "bodies.position": ["time"] + [f"bodies.position.{b}.{c}" for b in plot_big.BODIES for c in "xyz"],
            "left": ["time", "q.left", "qd.left", "qdd.left"] + [f"bodies.{k}.left.{c}" for k, p in
                                                              (("position", "xyz"), ("orientation", "wxyz"), ("com", "xyz"))
                                                              for c in p],
            "energy.total,time,q.left,energy.total": ["time", "energy.total", "q.left"],
            "momentum.angular": ["time"] + [f"momentum.angular.{c}" for c in "xyz"],
        }
        names, _, table = samples(self.run)
        for spec, want in cases.items():
            with self.subTest(spec=spec):
                out = self.path("c.csv")
                self.ok(self.run, "--csv", out, "--columns", spec)
                header, data = read_csv(out)
                got = [h.rsplit(" [", 1)[0] for h in header]
                self.assertEqual(got, want)
                self.assertTrue(same(data, table[:, [names.index(n) for n in want]]))
        # a joint's every coordinate: the free bus has 7 q, 6 qd, 6 qdd
        self.ok(self.run, "--csv", self.path("bus.csv"), "--columns", "bus", "--every", "1000")
        header, _ = read_csv(self.path("bus.csv"))
        self.assertEqual(sum(h.startswith("q.bus.") for h in header), 7)
        self.assertEqual(sum(h.startswith("qdd.bus.") for h in header), 6)

    def test_every(self):
        _, _, table = samples(self.run)
        for k in (1, 3, 499, 500, 10**9):
            with self.subTest(every=k):
                self.ok(self.run, "--csv", self.path("e.csv"), "--every", str(k), "--columns", "q.left")
                _, data = read_csv(self.path("e.csv"))
                self.assertTrue(same(data[:, 1], table[::k, 1 + 7]))
        self.refused(self.run, "--csv", self.path("e.csv"), "--every", "0", says="--every")

    def test_bad_column_is_one_line_and_writes_nothing(self):
        out = self.path("keep.csv")
        with open(out, "w") as f:
            f.write("mine\n")
        line = self.refused(self.run, "--csv", out, "--columns", "q.left,elbow", says="'elbow'")
        self.assertIn(self.run, line)
        self.assertEqual(open(out).read(), "mine\n")
        self.assertEqual(sorted(os.listdir(self.dir)), ["keep.csv", "run.h5"])

    def test_input_is_never_replaced(self):
        before = digest(self.run)
        self.refused(self.run, "--csv", self.run, says="input")
        os.symlink(self.run, self.path("alias.h5"))
        self.refused(self.run, "--json", self.path("alias.h5"), says="input")
        other = self.path("other.h5")
        plot_big.write_run(other, 3)
        self.refused(self.run, "--csv", other, says="HDF5")
        self.assertEqual(digest(self.run), before)

    def test_absent_and_foreign_files(self):
        self.refused(self.path("nope.h5"), "--csv", self.path("x.csv"), says="no such file")
        with open(self.path("text.h5"), "w") as f:
            f.write("not hdf5\n")
        self.refused(self.path("text.h5"), "--csv", self.path("x.csv"), says="not an HDF5 file")
        with h5py.File(self.path("bare.h5"), "w") as f:
            f["samples"] = np.zeros((3, 2))
        self.refused(self.path("bare.h5"), "--csv", self.path("x.csv"), says="column_names")
        self.refused(self.run, says="--csv")
        self.assertFalse(os.path.exists(self.path("x.csv")))


WRITER = r"""
import sys, time, h5py, numpy as np
path, w = sys.argv[1], 4
f = h5py.File(path, "w", libver="latest")
d = f.create_dataset("samples", (0, w), maxshape=(None, w), chunks=(64, w), dtype="f8")
d.attrs["column_names"] = ["time", "q.a", "q.b", "energy.total"]
d.attrs["column_units"] = ["s", "rad", "m", "J"]
f.swmr_mode = True
for k in range(100000):
    rows = np.arange(10 * k, 10 * k + 10, dtype=float)
    d.resize((10 * k + 10, w))
    d[10 * k:] = np.stack([rows * 0.01, np.sin(rows), np.cos(rows), rows / 3], axis=1)
    d.flush()
    if k == 2:
        print("flushed", flush=True)
    time.sleep(0.01)
"""


class Running(Base):
    def test_a_file_being_written(self):
        """an SWMR writer keeps appending: the export has at least the rows flushed before it
        started, each exactly as written, and the writer is not disturbed"""
        run = self.path("live.h5")
        w = subprocess.Popen([sys.executable, "-c", WRITER, run], stdout=subprocess.PIPE, text=True)
        try:
            self.assertEqual(w.stdout.readline().strip(), "flushed")
            counts = []
            for k in range(3):
                self.ok(run, "--csv", self.path(f"live{k}.csv"))
                _, data = read_csv(self.path(f"live{k}.csv"))
                r = np.arange(len(data), dtype=float)
                self.assertGreaterEqual(len(data), 30)
                self.assertTrue(same(data, np.stack([r * 0.01, np.sin(r), np.cos(r), r / 3], axis=1)))
                counts.append(len(data))
                time.sleep(0.2)
            self.assertGreater(counts[-1], counts[0], "the export saw no new rows")
            self.assertIsNone(w.poll(), "the writer stopped")
        finally:
            w.kill()
            w.wait()

    def test_a_soadyn_run_being_written(self):
        """a real run (10^4 s of the double pendulum, flushed every 0.05 s) exported mid-run"""
        run = self.path("dp.h5")
        p = subprocess.Popen([SOADYN, "run", os.path.join(ROOT, "scenarios", "double_pendulum.yaml"), "-o", run,
                              "--t-end", "10000", "--flush-interval", "0.05", "-q"], stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.time() + 60
            while not os.path.exists(run) and time.time() < deadline:
                time.sleep(0.05)
            time.sleep(0.3)
            self.ok(run, "--csv", self.path("dp.csv"), "--columns", "q,energy.total")
            header, data = read_csv(self.path("dp.csv"))
            self.assertIsNone(p.poll(), "the run ended before the export")
        finally:
            p.send_signal(signal.SIGINT)
            p.wait(timeout=60)
        self.assertEqual(header, ["time [s]", "q.theta1 [rad]", "q.theta2 [rad]", "energy.total [J]"])
        names, _, table = samples(run)  # the finished file has those rows and more
        self.assertGreater(len(data), 1)
        self.assertTrue(same(data, table[:len(data), [names.index(h.rsplit(" [", 1)[0]) for h in header]]))


class FullDisk(Base):
    """exit status 4 when the output cannot be written: one line, nothing half-written, an older
    file at the path unchanged (a real 1 MiB tmpfs filled up, and stdout on /dev/full)"""

    def setUp(self):
        super().setUp()
        self.run = self.path("run.h5")
        plot_big.write_run(self.run, 20000, ("state", "energy"))  # ~3 MiB of CSV: more than the disk

    def test_stdout_on_a_full_device(self):
        with open("/dev/full", "w") as full:
            p = subprocess.run([SOADYN, "export", self.run, "--csv", "-"], stdout=full, stderr=subprocess.PIPE,
                               text=True, timeout=60)
        self.assertEqual(p.returncode, 4, p.stderr)
        self.assertEqual(p.stderr.strip().splitlines(), ["soadyn: error: no space left on device while writing stdout"])

    def test_a_full_disk_leaves_the_older_file(self):
        if os.geteuid() != 0:
            self.skipTest("needs root to mount a 1 MiB tmpfs")
        mnt = self.path("mnt")
        os.mkdir(mnt)
        m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", mnt], capture_output=True, text=True)
        if m.returncode != 0:
            self.skipTest(f"cannot mount a tmpfs here: {m.stderr.strip()}")
        try:
            out = os.path.join(mnt, "x.csv")
            self.ok(self.run, "--csv", out, "--columns", "time", "--every", "1000")  # a small older file
            before = digest(out)
            p = export(self.run, "--csv", out)
            self.assertEqual(p.returncode, 4, p.stderr)
            lines = p.stderr.strip().splitlines()
            self.assertEqual(len(lines), 1, p.stderr)
            self.assertRegex(lines[0], rf"^soadyn: error: no space left on device while writing {re.escape(out)} "
                                       r"\(nothing written; an existing file there is unchanged\)$")
            self.assertEqual(digest(out), before)
            self.assertEqual(os.listdir(mnt), ["x.csv"])  # no temporary file left behind
        finally:
            subprocess.run(["umount", mnt])


class RealRun(Base):
    def test_every_column_of_a_satellite_run_against_the_views(self):
        run = self.path("sat.h5")
        p = subprocess.run([SOADYN, "run", os.path.join(ROOT, "scenarios", "satellite_two_arrays.yaml"), "--t-end", "2",
                            "-q", "-o", run], capture_output=True, text=True, timeout=300)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.ok(run, "--csv", self.path("sat.csv"))
        header, data = read_csv(self.path("sat.csv"))
        col = {h.rsplit(" [", 1)[0]: data[:, k] for k, h in enumerate(header)}
        with h5py.File(run, "r") as f:
            self.assertTrue(same(col["time"], f["time"][:]))
            q_names = [n.decode() for n in f["model"].attrs["q_names"]]
            q = f["q"][:]
            for k, n in enumerate(q_names):
                self.assertTrue(same(col["q." + n], q[:, k]), n)
            self.assertTrue(same(col["energy.total"], f["energy/total"][:]))
            self.assertTrue(same(col["momentum.angular.z"], f["momentum/angular"][:, 2]))
            units = dict(h[:-1].split(" [", 1) for h in header)
            self.assertEqual((units["q.left"], units["q.bus.x"], units["qd.bus.wx"], units["energy.total"]),
                             ("rad", "m", "rad/s", "J"))
        self.assertAlmostEqual(col["q.left"][0], 0.3, delta=1e-15)  # the scenario's initial state

    def test_a_prescribed_runs_holding_force_and_its_work(self):
        """the crane's trolley follows its slew: its drive's force (/prescribed) and W_p
        (/energy/work_prescribed) are columns of their own, named and in N and J"""
        run = self.path("crane.h5")
        p = subprocess.run([SOADYN, "run", os.path.join(ROOT, "scenarios", "crane_slew.yaml"), "--t-end", "8",
                            "-q", "-o", run], capture_output=True, text=True, timeout=300)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.ok(run, "--csv", self.path("crane.csv"), "--columns", "prescribed,energy.work_prescribed")
        header, data = read_csv(self.path("crane.csv"))
        self.assertEqual(header, ["time [s]", "prescribed.trolley [N]", "energy.work_prescribed [J]"])
        with h5py.File(run, "r") as f:
            self.assertTrue(same(data[:, 1], f["prescribed"][:, 0]))
            self.assertTrue(same(data[:, 2], f["energy/work_prescribed"][:]))
        # the trolley's drive pushes while it accelerates: a force of the order of (150 + 500) kg × q̈*
        self.assertGreater(np.abs(data[:, 1]).max(), 100.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
