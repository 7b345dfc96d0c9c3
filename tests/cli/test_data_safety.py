#!/usr/bin/python3
"""`soadyn run` never loses or corrupts its data: random SIGKILLs, signals, two runs on one path,
output = input, refused runs, a full disk, a scenario of 100 KiB, counts that overflow, settings
and a reader of a running run's file.  Real processes, real files."""
import fcntl
import glob
import hashlib
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import h5py
import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
SCENARIOS = os.path.join(ROOT, "scenarios")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import kill_loop  # noqa: E402

PENDULUM = os.path.join(SCENARIOS, "double_pendulum.yaml")
# 2e6 rk4 steps, a second or more: long enough to act on a running run
LONG = ["--method", "rk4", "--dt", "1e-5", "--t-end", "20", "--flush-interval", "0.05"]
# 10⁶ rk4 steps between two outputs
SLOW = ["--method", "rk4", "--dt", "1e-6", "--output-dt", "1", "--t-end", "100", "--flush-interval", "0.01"]


def run(*args, timeout=120):
    return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=timeout)


def read(path):
    with open(path) as f:
        return f.read()


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def wait_for(predicate, timeout=60.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.01)
    return False


class Base(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_safety_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def assertWhole(self, path, text=None, status=None):
        problems = kill_loop.check_file(path, text or read(PENDULUM))
        if status is None:
            self.assertEqual(problems, [], path)
        else:
            self.assertEqual([p for p in problems if not p.startswith("status")], [], path)
            with kill_loop.open_run_file(path) as f:
                self.assertRegex(f["solver/status"][()].decode(), status)

    def assertNoLitter(self, out):
        self.assertEqual(glob.glob(out + ".*"), [], "no temporary or lock file left")

    def old_file(self, name="out.h5"):
        out = self.path(name)
        p = run("run", PENDULUM, "--t-end", "0.5", "-q", "-o", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        return out, digest(out)

    def start(self, *args):
        return subprocess.Popen([SOADYN, "run", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


class KillLoop(unittest.TestCase):
    def test_one_hundred_random_sigkills(self):
        self.assertEqual(kill_loop.main(["--trials", "100", "--seed", "7", "--soadyn", SOADYN]), 0)


class Signals(Base):
    def test_sigint_sigterm_sighup_end_the_run_and_keep_the_file(self):
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            out = self.path(f"{sig.name}.h5")
            p = self.start(PENDULUM, *LONG, "-o", out)
            self.assertTrue(wait_for(lambda: os.path.exists(out)), "the file is put in place at the first flush")
            time.sleep(0.3)
            p.send_signal(sig)
            stdout, stderr = p.communicate(timeout=60)
            self.assertEqual(p.returncode, 128 + sig, stderr)
            m = re.search(rf"^soadyn: interrupted by {sig.name} at t = (\S+) \(logged up to there in {re.escape(out)}\)$",
                          stderr, re.M)
            self.assertIsNotNone(m, stderr)
            self.assertIn(f"status                 interrupted by {sig.name} at t = ", stdout)
            t = float(m.group(1))
            self.assertGreater(t, 0.0)
            self.assertLess(t, 20.0)
            self.assertWhole(out, status=rf"^interrupted by {sig.name} at t = ")
            with h5py.File(out, "r") as f:  # a run that ended by a signal closes its file: opens plainly
                self.assertAlmostEqual(f["time"][-1], t, delta=1e-8 * max(1, t))
                self.assertEqual(f["solver/t_reached"][()], f["time"][-1])
            self.assertNoLitter(out)

    def test_a_signal_ends_the_run_between_two_steps(self):
        # one output interval is 10⁶ steps (a second or more): the run must not wait for its end
        out = self.path("between.h5")
        p = self.start(PENDULUM, *SLOW, "-o", out)
        self.assertTrue(wait_for(lambda: os.path.exists(out)), "the file is put in place at the first output")
        time.sleep(0.2)
        p.send_signal(signal.SIGTERM)
        _, stderr = p.communicate(timeout=60)
        self.assertEqual(p.returncode, 143, stderr)
        self.assertWhole(out, status=r"^interrupted by SIGTERM at t = ")
        with h5py.File(out, "r") as f:
            t = f["time"][:]
            steps = int(f["solver/steps"][()])
        self.assertGreater(t[-1], t[-2])
        self.assertGreater(abs(t[-1] - round(t[-1])), 1e-4, f"the last row (t = {t[-1]}) is off the output grid")
        self.assertAlmostEqual(t[-1], steps * 1e-6, delta=1e-9 * steps, msg="the state after the last whole step")

    def test_a_second_signal_exits_at_once_and_the_file_reads(self):
        # SIGINT and SIGTERM sent together: two different signals are both delivered, the second
        # while the first has only set the stop flag, so the run leaves at once
        out = self.path("twice.h5")
        p = self.start(PENDULUM, *SLOW, "-o", out)
        self.assertTrue(wait_for(lambda: os.path.exists(out)))
        p.send_signal(signal.SIGINT)
        p.send_signal(signal.SIGTERM)
        _, stderr = p.communicate(timeout=60)
        self.assertIn(p.returncode, (130, 143), stderr)
        self.assertIn("interrupted twice", stderr)
        self.assertWhole(out, status="^running$")  # left at once: the status of its last flush
        self.assertFalse(os.path.exists(out + ".lock"))

        # before the first flush: the older file is kept byte for byte, nothing is left behind
        old, h = self.old_file("kept.h5")
        p = self.start(PENDULUM, *SLOW, "-o", old)
        self.assertTrue(wait_for(lambda: glob.glob(old + ".*.tmp")), "the file is being built")
        p.send_signal(signal.SIGINT)
        p.send_signal(signal.SIGTERM)
        _, stderr = p.communicate(timeout=60)
        self.assertIn(p.returncode, (130, 143), stderr)
        self.assertIn("interrupted twice", stderr)
        self.assertEqual(digest(old), h)
        self.assertNoLitter(old)

    def test_a_second_sigint_during_the_final_flush(self):
        # a row per step and no flush for minutes: the first SIGINT's final flush writes about a
        # second of rows, and a second SIGINT 20 ms later cuts it short; the file keeps its last flush
        buffered = ["--method", "rk4", "--dt", "1e-6", "--output-dt", "1e-6", "--t-end", "5",
                    "--flush-interval", "600", "--max-output-size", "4G"]
        twice = 0
        for trial in range(3):
            out = self.path(f"flush{trial}.h5")
            p = self.start(PENDULUM, *buffered, "-o", out)
            self.assertTrue(wait_for(lambda: os.path.exists(out)))
            time.sleep(1.0)
            p.send_signal(signal.SIGINT)
            time.sleep(0.02)
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
            _, stderr = p.communicate(timeout=60)
            self.assertEqual(p.returncode, 130, stderr)
            twice += "interrupted twice" in stderr
            self.assertWhole(out, status=r"^(running|interrupted by SIGINT at t = \S+)$")
            self.assertFalse(os.path.exists(out + ".lock"))
            if twice:
                break
        self.assertGreater(twice, 0, "the final flush was never caught by the second SIGINT")


class OneFile(Base):
    def test_two_runs_on_one_path(self):
        out = self.path("shared.h5")
        first = self.start(PENDULUM, *LONG, "-o", out)
        self.assertTrue(wait_for(lambda: os.path.exists(out)))
        second = run("run", os.path.join(SCENARIOS, "pendulum_on_cart.yaml"), "-o", out)
        self.assertEqual(second.returncode, 2, second.stderr)
        self.assertEqual(second.stderr.strip(),
                         f"soadyn: error: {out}: in use by another soadyn run (pid {first.pid}); "
                         "wait for it to end or choose another output")
        stdout, stderr = first.communicate(timeout=120)
        self.assertEqual(first.returncode, 0, stderr)
        self.assertWhole(out, status="^completed$")
        with h5py.File(out, "r") as f:
            self.assertEqual(len(f["time"]), 2001)
            self.assertEqual([n.decode() for n in f["model"].attrs["joint_names"]], ["theta1", "theta2"])
        self.assertNoLitter(out)

    def test_output_equal_to_an_input_is_refused(self):
        scenario = self.path("scene.yaml")
        shutil.copyfile(PENDULUM, scenario)
        h = digest(scenario)
        for out in (scenario, os.path.join(self.dir, ".", "..", os.path.basename(self.dir), "scene.yaml")):
            p = run("run", scenario, "-o", out)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn("the output is the input file", p.stderr)
        self.assertEqual(digest(scenario), h)
        # a URDF the scenario names is an input too: never replaced, --force or not
        urdf = self.path("robot.urdf")
        with open(urdf, "w") as f:
            f.write('<robot name="r"><link name="a"/><link name="b"><inertial><mass value="1"/>'
                    '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                    '<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/></joint></robot>')
        with open(self.path("urdf_scene.yaml"), "w") as f:
            f.write("urdf: robot.urdf\nsimulation: {t_end: 0.1}\n")
        hu = digest(urdf)
        for force in ([], ["--force"]):
            p = run("run", self.path("urdf_scene.yaml"), "-o", urdf, *force)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn("the output is the input file", p.stderr)
            self.assertEqual(digest(urdf), hu)
        self.assertNoLitter(urdf)

    def test_a_refused_run_leaves_an_existing_file_unchanged(self):
        out, h = self.old_file()
        weld = self.path("weld.yaml")
        with open(weld, "w") as f:
            f.write("bodies:\n  - {name: plate, joint: {type: fixed}, mass: 1.0, inertia: [0.1, 0.1, 0.1]}\n")
        refusals = [
            ([PENDULUM, "--rtol", "10"], "rtol must lie in (0, 1), got 10"),
            ([PENDULUM, "--output-dt", "1e-6", "--max-output-size", "1M"], "more than --max-output-size 1M"),
            ([weld], "no degrees of freedom"),
            ([self.path("missing.yaml")], "cannot open the file"),
        ]
        for args, expect in refusals:
            p = run("run", *args, "-o", out)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn(expect, p.stderr)
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
            self.assertEqual(digest(out), h, args)
            self.assertNoLitter(out)
        # held by another process (the lock names its pid)
        with open(out + ".lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            lock.write("4242\n")
            lock.flush()
            p = run("run", PENDULUM, "-o", out)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn(f"{out}: in use by another soadyn run (pid 4242)", p.stderr)
        self.assertEqual(digest(out), h)


class FullDisk(Base):
    def setUp(self):
        super().setUp()
        if os.geteuid() != 0:
            self.skipTest("needs root to mount a 1 MiB tmpfs")
        self.mnt = self.path("mnt")
        os.mkdir(self.mnt)
        p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", self.mnt], capture_output=True, text=True)
        if p.returncode != 0:
            self.skipTest(f"cannot mount a tmpfs here: {p.stderr.strip()}")

    def tearDown(self):
        subprocess.run(["umount", self.mnt])
        super().tearDown()

    def test_a_full_disk_gives_one_line_and_keeps_the_flushed_rows(self):
        out = os.path.join(self.mnt, "x.h5")
        p = run("run", os.path.join(SCENARIOS, "satellite_two_arrays.yaml"), "--method", "rk4", "--dt", "1e-4",
                "--t-end", "20", "--output-dt", "1e-3", "--flush-interval", "0.02", "-q", "-o", out)
        self.assertEqual(p.returncode, 4, p.stderr)
        lines = p.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, p.stderr)
        m = re.fullmatch(rf"soadyn: error: no space left on device while writing {re.escape(out)} at t = (\S+) s "
                         r"\(rows up to t = (\S+) s are kept\)", lines[0])
        self.assertIsNotNone(m, lines[0])
        kept = float(m.group(2))
        self.assertLessEqual(kept, float(m.group(1)))
        self.assertWhole(out, read(os.path.join(SCENARIOS, "satellite_two_arrays.yaml")))
        with kill_loop.open_run_file(out) as f:
            self.assertAlmostEqual(f["time"][-1], kept, delta=1e-9)
            self.assertGreater(len(f["time"]), 100)
        self.assertFalse(os.path.exists(out + ".lock"))

    def test_a_full_disk_while_creating_leaves_the_older_file(self):
        out = os.path.join(self.mnt, "x.h5")
        p = run("run", PENDULUM, "--t-end", "0.5", "-q", "-o", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        h = digest(out)
        try:  # fill the disk
            with open(os.path.join(self.mnt, "filler"), "wb") as f:
                while True:
                    f.write(b"\0" * 4096)
                    f.flush()
        except OSError:
            pass
        p = run("run", PENDULUM, "--t-end", "0.5", "-q", "-o", out)
        self.assertEqual(p.returncode, 4, p.stderr)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        self.assertRegex(p.stderr, rf"^soadyn: error: no space left on device while (creating|writing) {re.escape(out)}.*"
                                   r"the output was not written; an existing file there is unchanged")
        self.assertEqual(digest(out), h)
        self.assertNoLitter(out)


class Contents(Base):
    def test_a_scenario_of_100_kib_is_kept_whole(self):
        text = read(PENDULUM) + "".join(f"# comment line {k:06d} " + "x" * 80 + "\n" for k in range(1100))
        self.assertGreater(len(text.encode()), 100 * 1024)
        scenario = self.path("big.yaml")
        with open(scenario, "w") as f:
            f.write(text)
        out = self.path("big.h5")
        p = run("run", scenario, "--t-end", "0.1", "-q", "-o", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertWhole(out, text, status="^completed$")

    def test_a_reader_opens_a_running_runs_file(self):
        out = self.path("live.h5")
        p = self.start(PENDULUM, *LONG, "-o", out)
        self.assertTrue(wait_for(lambda: os.path.exists(out)))
        seen = []
        for _ in range(3):
            time.sleep(0.2)
            with h5py.File(out, "r", swmr=True) as f:
                n = {len(f[s]) for s in kill_loop.SERIES}
                self.assertEqual(len(n), 1, "one length for every series")
                seen.append(n.pop())
                self.assertEqual(f["solver/status"][()], b"running")
        env = dict(os.environ, MPLBACKEND="Agg")
        plot = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "tools", "plot.py"), out, "-o", self.path("live.png")],
                              capture_output=True, text=True, env=env, timeout=120)
        self.assertEqual(plot.returncode, 0, plot.stderr)
        self.assertGreater(os.path.getsize(self.path("live.png")), 1000)
        p.communicate(timeout=120)
        self.assertEqual(p.returncode, 0)
        self.assertGreater(seen[-1], seen[0], "rows appear while the run goes")


class Settings(Base):
    def refused(self, *args, expect):
        p = run("run", PENDULUM, *args, "-o", self.path("s.h5"))
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn(expect, p.stderr)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        self.assertFalse(os.path.exists(self.path("s.h5")))

    def test_tolerances(self):
        self.refused("--rtol", "10", expect="rtol must lie in (0, 1), got 10")
        self.refused("--rtol", "1", expect="rtol must lie in (0, 1), got 1")
        p = run("run", PENDULUM, "--rtol", "1e-20", "--t-end", "1e-4", "-o", self.path("tight.h5"))
        self.assertIn("soadyn: warning: rtol 1e-20 is below what double precision can deliver", p.stderr)
        self.assertIn("(rtol 1e-20, atol 1e-12)", p.stdout, "tolerances printed with %g")

    def test_counts_that_overflow(self):
        scenario = self.path("huge.yaml")
        with open(scenario, "w") as f:
            f.write(re.sub(r"t_end: [0-9.]+", "t_end: 1.0e+308", read(PENDULUM)))
        self.assertIn("t_end: 1.0e+308", read(scenario))
        p = run("run", scenario, "--method", "rk4", "-o", self.path("s.h5"))
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn("more than 2^53", p.stderr)
        self.refused("--t-end", "1e10", "--output-dt", "1e-9", expect="more than 2^53")
        self.refused("--method", "rk4", "--t-end", "1e6", "--dt", "1e-12", "--output-dt", "1e5", expect="steps, more than 2^53")

    def test_projected_size(self):
        self.refused("--output-dt", "1e-9", "--t-end", "10", expect="more than --max-output-size 1G")
        # 100001 rows of 38 doubles (t, q 2, qd 2, qdd 2, energy 5, momentum 6, bodies 2 x 10): 29 MiB
        self.refused("--output-dt", "1e-4", "--max-output-size", "10M", expect="29 MiB (100001 rows of 304 bytes)")
        # a lean log is smaller: t, q, qd, qdd and the energies, 12 doubles, 9.16 MiB
        p = run("run", PENDULUM, "--output-dt", "1e-4", "--max-output-size", "10M", "--log", "state,energy", "-q",
                "-o", self.path("lean.h5"))
        self.assertEqual(p.returncode, 0, p.stderr)
        with h5py.File(self.path("lean.h5"), "r") as f:
            self.assertEqual(f["samples"].shape, (100001, 12))
            self.assertEqual(f.attrs["log_groups"].decode(), "state,energy")
            self.assertNotIn("bodies", f)
            self.assertNotIn("momentum", f)
        p = run("run", PENDULUM, "--output-dt", "1e-4", "--t-end", "0.01", "--max-output-size", "10M", "-q",
                "-o", self.path("ok.h5"))
        self.assertEqual(p.returncode, 0, p.stderr)
        self.refused("--max-output-size", "lots", expect="expected a size such as 800M or 2G, got 'lots'")

    def test_options_without_effect_are_warned(self):
        p = run("run", PENDULUM, "--method", "rk4", "--rtol", "1e-6", "--t-end", "0.01", "-q", "-o", self.path("a.h5"))
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("soadyn: warning: --rtol has no effect with rk4", p.stderr)
        p = run("run", PENDULUM, "--dt", "1e-3", "--t-end", "0.01", "-q", "-o", self.path("b.h5"))
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("soadyn: warning: --dt has no effect with cvode-adams", p.stderr)
        p = run("run", PENDULUM, "--t-end", "0.01", "-q", "-o", self.path("c.h5"))
        self.assertEqual(p.stderr, "", "no warning without a reason")


class Messages(Base):
    def write(self, name, data):
        with open(self.path(name), "wb") as f:
            f.write(data)
        return self.path(name)

    def refused(self, *args, expect):
        p = run(*args)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertEqual(p.stderr.strip().splitlines(), [f"soadyn: error: {expect}"])

    def test_numbers_overflow_and_names(self):
        body = "bodies:\n  - {name: a, joint: {type: revolute, axis: AXIS}, mass: 1, inertia: [1, 1, 1]}\n"
        tiny = self.write("tiny.yaml", body.replace("AXIS", "[1.0e-320, 0, 0]").encode())
        self.refused("run", tiny, expect=f"{tiny}:2:45: body 'a'.joint.axis: expected a non-zero axis of norm between 1e-12 "
                                         "and 1e150, got [9.99989e-321, 0, 0]")
        huge = self.write("huge.yaml", body.replace("AXIS", "[1.0e+200, 1.0e+200, 0]").encode())
        self.refused("inspect", huge, expect=f"{huge}:2:45: body 'a'.joint.axis: expected a non-zero axis of norm between "
                                             "1e-12 and 1e150, got [1e+200, 1e+200, 0]")
        bad = self.write("names.yaml", body.replace("AXIS", "[1, 0, 0]").replace("name: a", "name: a\xff\xfeb")
                         .encode("latin-1"))
        for cmd in ("run", "inspect"):  # refused where the model is built, for every command
            p = run(cmd, bad)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertRegex(p.stderr.strip(), r"^soadyn: error: " + re.escape(bad) +
                             r":2:\d+: body 'a\\xff\\xfeb': name: expected a valid UTF-8 name, got 'a\\xff\\xfeb'$")
        urdf = self.write("names.urdf", '<robot name="r"><link name="base"/><link name="a\xffb"><inertial><mass value="1"/>'
                          '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>\n'
                          '<joint name="j" type="revolute"><parent link="base"/><child link="a\xffb"/><axis xyz="1 0 0"/>'
                          '<limit effort="1" velocity="1" lower="-1" upper="1"/></joint></robot>\n'.encode("latin-1"))
        p = run("inspect", urdf)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("expected a valid UTF-8 name, got 'a\\xffb'", p.stderr)
        quat = self.write("quat.yaml", b"bodies:\n  - {name: f, joint: {type: free}, mass: 1, inertia: [1, 1, 1]}\n"
                                       b"initial:\n  q: {f: [0, 0, 0, 0, 0, 0, 0]}\n")
        p = run("run", quat)
        self.assertIn("expected a unit quaternion [w, x, y, z] after the position, got norm 0", p.stderr)
        self.assertNotIn("0.000000", p.stderr)

    def test_urdf_overflow_and_xml_bomb(self):
        link = '<link name="{}"><inertial>{}<mass value="{}"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>' \
               '</inertial></link>'
        urdf = ('<robot name="r"><link name="a"/>\n' + link.format("b", "", "1") + "\n" +
                link.format("c", '<origin xyz="0 0 -1"/>', "1e308") + "\n"
                '<joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/></joint>\n'
                '<joint name="w" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0 0 -1"/></joint></robot>\n')
        heavy = self.write("heavy.urdf", urdf.encode())
        p = run("inspect", heavy)
        self.assertEqual(p.returncode, 2)
        self.assertIn("link 'c': mass: expected at most 1e50 kg, got 1e+308", p.stderr)
        self.assertNotIn("nan", p.stderr)
        bomb = self.write("bomb.urdf", b'<?xml version="1.0"?>\n<!DOCTYPE r [\n <!ENTITY a "aaaaaaaaaa">\n'
                                       b' <!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">\n]>\n<robot name="&b;"/>\n')
        self.refused("inspect", bomb, expect=f"{bomb}:3: XML: entity declarations (<!ENTITY ...>) are refused: a URDF "
                                             "needs none, and nested ones expand without bound (an XML bomb)")

    def test_stale_temporary_files_are_removed(self):
        out = self.path("o.h5")
        for name in ("o.h5.123.tmp", "o.h5.77.tmp"):
            self.write(name, b"half-built")
        self.write("o.h5.notes.tmp", b"someone else's")
        p = run("run", PENDULUM, "--t-end", "0.1", "-q", "-o", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(sorted(os.listdir(self.dir)), ["o.h5", "o.h5.notes.tmp"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
