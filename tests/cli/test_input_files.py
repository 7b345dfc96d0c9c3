#!/usr/bin/python3
"""Inputs that would block, grow without bound or stall a run: every reader of a user's file (a
scenario's table target, an MJCF model's <include>s and meshes, the run files of view, export,
identify --data and read_log) meets a FIFO, /dev/zero, a directory, symlinks to each, a missing and
an oversized file, and must end within 10 s with exit 2 and one line naming the file and the
reason; tables with repeated or too-close times and control_dt values that ask for too many ticks
are refused naming file, line and field (or the option) before any file is written.  Real
processes and real files: a hang is a timeout, which fails the test rather than blocking CI."""
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import unittest

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PYTHONPATH = os.environ.get("SOADYN_PYTHONPATH", os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))
PENDULUM = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
LIMIT_S = 10


def run(*args, env=None):
    """soadyn with a hard timeout: a blocked reader raises TimeoutExpired (the test fails)"""
    t0 = time.monotonic()
    r = subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=LIMIT_S, env=env)
    r.seconds = time.monotonic() - t0
    return r


def text(path):
    with open(path) as f:
        return f.read()


def stl(path, scale):
    """a binary STL tetrahedron with edges `scale` m long along the axes"""
    v = [(0, 0, 0), (scale, 0, 0), (0, scale, 0), (0, 0, scale)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for a, b, c in faces:
            f.write(struct.pack("<3f", 0, 0, 0))
            for k in (a, b, c):
                f.write(struct.pack("<3f", *v[k]))
            f.write(b"\0\0")


class Base(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_inputs_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, *names):
        return os.path.join(self.dir, *names)

    def write(self, name, text):
        p = self.path(name)
        os.makedirs(os.path.dirname(p), exist_ok=True)
        with open(p, "w") as f:
            f.write(text)
        return p

    def refused(self, r, *patterns):
        """exit 2 within the limit, one line on stderr matching every pattern, nothing on stdout"""
        self.assertLess(r.seconds, LIMIT_S)
        self.assertEqual(r.returncode, 2, r.stdout + r.stderr)
        lines = [line for line in r.stderr.splitlines() if line.strip()]
        self.assertEqual(len(lines), 1, r.stderr)
        for p in patterns:
            self.assertRegex(lines[0], p)
        self.assertNotIn("Traceback", r.stderr)
        return lines[0]

    def odd_files(self, big_mib=65, limit_mib=64):
        """(path, reason) for each kind of file that is not a regular one, links to them, a missing
        file and one of big_mib MiB (sparse) past a limit of limit_mib"""
        fifo, folder = self.path("odd", "fifo"), self.path("odd", "folder")
        os.makedirs(folder, exist_ok=True)
        if not os.path.exists(fifo):
            os.mkfifo(fifo)
        cases = [(fifo, r"not a regular file \(a FIFO\)"), (folder, r"is a directory"),
                 ("/dev/zero", r"not a regular file \(a character device\)"),
                 (self.path("odd", "missing"), r"cannot open the file \(no such file or directory\)")]
        for target, why in list(cases[:3]):
            link = self.path("odd", "link_to_" + os.path.basename(target))
            if not os.path.lexists(link):
                os.symlink(target, link)
            cases.append((link, why))
        big = self.path("odd", f"big{big_mib}")
        with open(big, "wb") as f:
            f.truncate(big_mib << 20)  # sparse: NULs, no disk
        cases.append((big, rf"{big_mib} MiB, more than the {limit_mib} MiB allowed"))
        return cases


class TableTargets(Base):
    """a PD target {table: FILE, column: theta1} (src/algorithm/table.cpp)"""

    def scene(self, table):
        return self.write("follow.yaml", text(PENDULUM) + "\ninputs:\n  controllers:\n    - {type: pd, joint: theta1, kp: 10, kd: 1, "
                                                "target: {table: " + json.dumps(table) + ", column: theta1}}\n")

    def test_fifo_device_directory_links_missing_and_oversized_tables(self):
        out = self.path("o.h5")
        cases = self.odd_files()
        for table, why in cases:
            with self.subTest(table=table):
                for cmd in (["inspect", self.scene(table)], ["run", self.scene(table), "-o", out, "-q"]):
                    line = self.refused(run(*cmd), re.escape(table) + ": " + why, r"follow\.yaml:\d+:\d+: .*table")
                    self.assertNotIn("the table is empty", line)
        self.assertFalse(os.path.exists(out))
        self.assertEqual(len(cases), 8)

    def times(self, rows):
        return self.write("tab.csv", "t, theta1\n" + "".join(f"{t!r}, {q}\n" for t, q in rows))

    def test_repeated_close_and_decreasing_times_name_file_line_and_column(self):
        cases = [([(0, 0), (0.5, 1), (0.5, 2), (1, 0)], r"tab\.csv:4: column 't': the time 0\.5 repeats line 3's"),
                 ([(0, 0), (0.5, 1), (0.5 + 1e-16, 2), (1, 0)], r"tab\.csv:4: column 't': 0\.50000000000000011 is 1\.11022e-16 s "
                                                                  r"after line 3's 0\.5, closer than the 1e-09 s"),
                 ([(0, 0), (1, 1), (0.5, 2)], r"tab\.csv:4: column 't': the time decreases \(1 at line 3, then 0\.5\)"),
                 # a jump sampled 1 ms wide beside 0.5 s: the spline rings 96 times the range (60 000 steps where 1 500 do)
                 ([(0, 0), (0.5, 0), (0.501, 1), (1, 1)], r"tab\.csv:3: column 'theta1': the spline through the samples strays "
                                                          r"96\.1291 beyond their range \[0, 1\] .*0\.001 s before line 4")]
        for rows, why in cases:
            with self.subTest(rows=rows):
                self.times(rows)
                self.refused(run("run", self.scene("tab.csv"), "-o", self.path("o.h5"), "-q"), why)
        self.assertFalse(os.path.exists(self.path("o.h5")))
        # twice the minimum spacing: accepted, and the run ends
        self.times([(0, 0), (0.5, 1), (0.5 + 2e-9, 1), (1, 0)])
        r = run("run", self.scene("tab.csv"), "-o", self.path("ok.h5"), "-q", "--t-end", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertLess(r.seconds, LIMIT_S)


class MjcfFiles(Base):
    """an MJCF model's <include> and <mesh> files, read by us and handed to MuJoCo (src/io/mjcf_vfs.cpp)"""

    MODEL = ('<mujoco>\n  <compiler meshdir="{meshdir}"/>\n  <asset>{assets}</asset>\n  <worldbody>\n'
             '    <body name="a"><joint name="ja" type="hinge" axis="0 1 0"/>{geoms}</body>\n'
             '    {include}\n  </worldbody>\n</mujoco>\n')

    def model(self, name="robot.xml", meshdir="meshes", meshes=(), include=""):
        assets = "".join(f'<mesh name="m{k}" file="{f}"/>' for k, f in enumerate(meshes))
        geoms = "".join(f'<geom type="mesh" mesh="m{k}" density="1000"/>' for k in range(len(meshes))) or \
            '<geom type="sphere" size="0.1" pos="0 0 -0.5"/>'
        inc = f'<include file="{include}"/>' if include else ""
        return self.write(name, self.MODEL.format(meshdir=meshdir, assets=assets, geoms=geoms, include=inc))

    def test_include_and_mesh_files_that_are_not_regular(self):
        # an include is named from the model's folder (MuJoCo 2.2 joins even an absolute name to it)
        includes = [c for c in self.odd_files() if c[0].startswith(self.dir)]
        for target, why in includes:
            with self.subTest(include=target):
                self.refused(run("inspect", self.model(include=os.path.relpath(target, self.dir))),
                             re.escape(target) + ": " + why)
        meshes = self.odd_files(257, 256)
        for target, why in meshes:
            name = os.path.relpath(target, self.dir) if target.startswith(self.dir) else target
            with self.subTest(mesh=target):
                self.refused(run("inspect", self.model(meshdir="", meshes=[name])), re.escape(target) + ": " + why)
        self.assertEqual((len(includes), len(meshes)), (7, 8))
        # through a scenario's model: key, the same line naming the scenario too
        scene = self.write("scene.yaml", "model: robot.xml\n")
        self.model(include="odd/fifo")
        self.refused(run("inspect", scene), r"scene\.yaml:1:\d+: model: .*odd/fifo: not a regular file \(a FIFO\)")

    def test_meshes_and_includes_load_from_memory_as_from_disk(self):
        os.makedirs(self.path("meshes", "a"))
        os.makedirs(self.path("meshes", "b"))
        stl(self.path("meshes", "a", "part.stl"), 0.2)
        stl(self.path("meshes", "b", "part.stl"), 0.4)  # the same name in another folder
        stl(self.path("meshes", "big.stl"), 0.4)
        self.write("parts.xml", '<mujoco><body name="c" pos="0 0 -1"><joint name="jc" type="slide" axis="0 0 1"/>'
                                '<geom type="box" size="0.1 0.1 0.1"/></body></mujoco>\n')

        def mass_matrix(meshes):
            r = run("inspect", self.model(meshes=meshes, include="parts.xml"), "--json")
            self.assertEqual(r.returncode, 0, r.stderr)
            return json.loads(r.stdout)["M"]

        twins = mass_matrix(["a/part.stl", "b/part.stl"])
        self.assertEqual(len(twins), 2)  # ja and the included body's slide
        # b/part.stl is the 0.4 m tetrahedron, not a/part.stl read twice
        self.assertAlmostEqual(twins[0][0], mass_matrix(["a/part.stl", "big.stl"])[0][0], delta=1e-9 * twins[0][0])
        self.assertGreater(twins[0][0], mass_matrix(["a/part.stl", "a/part.stl"])[0][0] * 1.5)


class RunFiles(Base):
    """view, export, identify --data, tools/plot.py and Python's read_log on files that are not run files"""

    def test_every_run_file_reader(self):
        env = dict(os.environ, PYTHONPATH=PYTHONPATH)
        reader = ("import sys, soadyn\ntry:\n    soadyn.read_log(sys.argv[1])\nexcept soadyn.Error as e:\n"
                  "    print(e, file=sys.stderr); sys.exit(2)\n")
        cases = [c for c in self.odd_files() if "MiB" not in c[1]]  # a run file has no size limit
        for target, why in cases:
            for cmd in (["view", target, "-o", self.path("x.html")], ["export", target, "--csv", self.path("x.csv")],
                        ["identify", PENDULUM, "--data", target, "--parameters", "upper"]):
                with self.subTest(cmd=cmd):
                    self.refused(run(*cmd), re.escape(target) + ": " + why)
            with self.subTest(plot=target):  # tools/plot.py (h5py would wait on a FIFO)
                t0 = time.monotonic()
                r = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "plot.py"), target, "-o", self.path("x.png")],
                                   capture_output=True, text=True, timeout=LIMIT_S, env=dict(os.environ, MPLBACKEND="Agg"))
                r.seconds = time.monotonic() - t0
                self.refused(r, "^plot.py: error: " + re.escape(target) + ": " + why)
            with self.subTest(read_log=target):
                t0 = time.monotonic()
                r = subprocess.run([sys.executable, "-c", reader, target], capture_output=True, text=True,
                                   timeout=LIMIT_S, env=env)
                r.seconds = time.monotonic() - t0
                self.refused(r, re.escape(target) + ": cannot read the run file: .*" + why.split(r" \(")[0])
        self.assertFalse(os.path.exists(self.path("x.html")) or os.path.exists(self.path("x.csv")) or
                         os.path.exists(self.path("x.png")))
        self.assertEqual(len(cases), 7)


class ControlTicks(Base):
    """control_dt bounded as steps and rows are: at most 10^8 ticks over t_end"""

    def test_too_many_ticks_are_refused_before_anything_is_written(self):
        out = self.path("o.h5")
        scene = self.write("ctl.yaml", text(PENDULUM) +
                           "\ninputs:\n  controllers:\n    - {type: pd, joint: theta1, kp: 10, kd: 1, target: 0}\n")
        for value in ("1e-9", "1e-300", "5e-324"):
            with self.subTest(control_dt=value):
                self.refused(run("run", scene, "--control-dt", value, "-o", out, "-q"),
                             r"^soadyn: error: --control-dt: control_dt \S+ s over t_end 10 s is \S+ controller ticks, "
                             r"more than the 1e\+08")
        self.refused(run("run", scene, "--control-dt", "1e-6", "--t-end", "1e3", "-o", out, "-q"),
                     r"--control-dt: control_dt 1e-06 s over t_end 1000 s is 1e\+09 controller ticks")
        # the scenario's own field, with its line; a --t-end that makes a scenario's ticks too many
        with_dt = self.write("ctl_dt.yaml", text(scene).replace("output_dt: 0.01", "output_dt: 0.01\n  control_dt: 1.0e-9"))
        self.refused(run("run", with_dt, "-o", out, "-q"), r"ctl_dt\.yaml:\d+:\d+: simulation\.control_dt: control_dt 1e-09 s")
        self.refused(run("inspect", with_dt), r"ctl_dt\.yaml:\d+:\d+: simulation\.control_dt:")
        self.refused(run("run", scene, "--control-dt", "1e-3", "--t-end", "1e6", "-o", out, "-q"), r"--control-dt: .* 1e\+09 controller")
        self.assertFalse(os.path.exists(out))
        # 10^4 ticks: runs
        r = run("run", scene, "--control-dt", "1e-4", "--t-end", "1", "-o", out, "-q")
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main()
