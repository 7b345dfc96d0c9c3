#!/usr/bin/python3
"""Files that aren't the run's own: no writer (run, view, export, identify, Python simulate(output=),
sweep) writes through a symlinked, FIFO, hard-linked or foreign lock file or temporary name; a sweep
never replaces a DIR/results.h5 it did not write (unless forced); no output lands on a file the
scenario was read from (its robot, MJCF includes and meshes, target tables), --force or not; a
scenario's name never leads the default output out of out/; and --max-output-size counts every
logged series (sensitivities, frames) before anything is touched.  Real processes, real files."""
import hashlib
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

import h5py

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PENDULUM = os.path.join(ROOT, "scenarios", "double_pendulum.yaml")
ARM_URDF = os.path.join(ROOT, "scenarios", "two_link_arm.urdf")
PYTHONPATH = os.environ.get("SOADYN_PYTHONPATH", os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))
ENV = dict(os.environ, PYTHONPATH=PYTHONPATH)
PRECIOUS = b"precious: not soadyn's\n"
# Python's soadyn.simulate(SCENE, output=OUT, t_end=...) as a process: exit 2 and one line on soadyn.Error
SIMULATE = ("import sys, soadyn\ntry:\n    soadyn.simulate(sys.argv[1], output=sys.argv[2], t_end=0.05)\n"
            "except soadyn.Error as e:\n    print(e, file=sys.stderr); sys.exit(2)\n")


def run(*args, timeout=60, **kw):
    return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=timeout, env=ENV, **kw)


def simulate(scene, out, **kw):
    return subprocess.run([sys.executable, "-c", SIMULATE, scene, out], capture_output=True, text=True, timeout=60,
                          env=ENV, **kw)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


class Base(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_links_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def write(self, name, data):
        with open(self.path(name), "wb" if isinstance(data, bytes) else "w") as f:
            f.write(data)
        return self.path(name)

    def victim(self, name="victim.txt"):
        return self.write(name, PRECIOUS)

    def make_run(self, name="r.h5", scene=PENDULUM):
        r = run("run", scene, "-o", self.path(name), "-q", "--t-end", "0.2")
        self.assertEqual(r.returncode, 0, r.stderr)
        return self.path(name)

    def assertRefused(self, r, pattern, code=2):
        self.assertEqual(r.returncode, code, r.stdout + r.stderr)
        lines = [line for line in r.stderr.splitlines() if line.strip()]
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertRegex(lines[0], pattern)
        self.assertNotIn("Traceback", r.stderr)

    def writers(self, out):
        """every writing command, each aimed at `out`: (label, a function running it)"""
        run_file = self.make_run("in.h5")
        return [
            ("export --csv", lambda: run("export", run_file, "--csv", out, "-q")),
            ("export --json", lambda: run("export", run_file, "--json", out, "-q")),
            ("run -o", lambda: run("run", PENDULUM, "-o", out, "-q", "--t-end", "0.05")),
            ("view -o", lambda: run("view", run_file, "-o", out, "-q")),
            ("identify -o", lambda: run("identify", PENDULUM, "--data", run_file, "--parameters", "lower", "-o", out, "-q")),
            ("simulate(output=)", lambda: simulate(PENDULUM, out)),
        ]


class Locks(Base):
    def test_a_symlinked_lock_is_refused_by_every_writer(self):
        """6 writers x (a link to a file, a dangling link): exit 2, one line, the target untouched or not made"""
        out = self.path("o.out")
        for label, command in self.writers(out):
            for dangling in (False, True):
                with self.subTest(label, dangling=dangling):
                    target = self.path("absent.txt") if dangling else self.victim()
                    os.symlink(target, out + ".lock")
                    self.assertRefused(command(), r"o\.out\.lock: a symbolic link where soadyn keeps its lock")
                    if dangling:
                        self.assertFalse(os.path.lexists(target), "the link's target was created")
                    else:
                        with open(target, "rb") as f:
                            self.assertEqual(f.read(), PRECIOUS)
                    self.assertFalse(os.path.exists(out), "nothing written")
                    self.assertTrue(os.path.islink(out + ".lock"), "the link is left as it was")
                    os.unlink(out + ".lock")

    def test_a_lock_that_is_not_a_lock_file_is_refused(self):
        """a FIFO, a directory, a hard link to a file, a file with other text: 4 kinds x run -o and export"""
        out = self.path("o.out")
        run_file = self.make_run("in.h5")
        commands = [lambda: run("run", PENDULUM, "-o", out, "-q", "--t-end", "0.05"),
                    lambda: run("export", run_file, "--csv", out, "-q")]
        for kind, pattern in (("fifo", r"not a regular file"), ("dir", r"a directory"), ("hard", r"has 2 names"),
                              ("text", r"holds something other than a soadyn writer's pid")):
            for command in commands:
                with self.subTest(kind):
                    lock = out + ".lock"
                    if kind == "fifo":
                        os.mkfifo(lock)
                    elif kind == "dir":
                        os.mkdir(lock)
                    elif kind == "hard":
                        os.link(self.victim(), lock)
                    else:
                        self.write("o.out.lock", PRECIOUS)
                    self.assertRefused(command(), "o\\.out\\.lock: " + pattern)
                    self.assertFalse(os.path.exists(out))
                    if kind == "hard":
                        self.assertEqual(digest(self.path("victim.txt")), hashlib.sha256(PRECIOUS).hexdigest())
                    shutil.rmtree(lock) if kind == "dir" else os.unlink(lock)

    def test_a_killed_writers_lock_is_taken_over(self):
        """the file a SIGKILLed writer leaves (its pid) is soadyn's own: taken, and removed at the end"""
        out = self.path("o.h5")
        self.write("o.h5.lock", "999999\n")
        r = run("run", PENDULUM, "-o", out, "-q", "--t-end", "0.05")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertFalse(os.path.lexists(out + ".lock"))

    def test_symlinked_temporary_names_are_never_written_through(self):
        """'<out>.<pid>.tmp' links for the next pids: run -o, export, view and simulate(output=) leave the target as it was"""
        run_file = self.make_run("in.h5")
        cases = [("o.h5", lambda o: [SOADYN, "run", PENDULUM, "-o", o, "-q", "--t-end", "0.05"]),
                 ("o.csv", lambda o: [SOADYN, "export", run_file, "--csv", o, "-q"]),
                 ("o.html", lambda o: [SOADYN, "view", run_file, "-o", o, "-q"]),
                 ("p.h5", lambda o: [sys.executable, "-c", SIMULATE, PENDULUM, o])]
        for name, argv in cases:
            with self.subTest(name):
                victim = self.victim()
                out = self.path(name)
                with open("/proc/sys/kernel/ns_last_pid") as f:
                    last = int(f.read())
                for pid in range(last + 1, last + 400):
                    os.symlink(victim, f"{out}.{pid}.tmp")
                p = subprocess.Popen(argv(out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
                _, err = p.communicate(timeout=60)
                self.assertEqual(p.returncode, 0, err)
                self.assertIn(p.pid, range(last + 1, last + 400), "the writer's own temporary name was a link")
                with open(victim, "rb") as f:
                    self.assertEqual(f.read(), PRECIOUS)
                self.assertTrue(os.path.isfile(out) and not os.path.islink(out))
                self.assertEqual([n for n in os.listdir(self.dir) if n.endswith(".tmp")], [], "the links are gone")


class InputsAsOutputs(Base):
    """Every file the scenario reads is an input: refused as an output with --force, under any name."""

    def scene_with_everything(self):
        """a URDF scene whose PD targets read a CSV and a run file; an MJCF scene with an include and a mesh"""
        shutil.copy(ARM_URDF, self.path("arm.urdf"))
        self.write("table.csv", "time [s],shoulder [rad]\n0,0\n0.5,0.2\n1,0.1\n")
        self.make_run("own.h5", self.write("targets.yaml", "urdf: arm.urdf\n"))
        self.write("arm.yaml", "urdf: arm.urdf\nsimulation: {t_end: 0.05}\ninputs:\n  controllers:\n"
                   "    - {type: pd, joint: shoulder, kp: 10, kd: 1, target: {table: table.csv}}\n"
                   "    - {type: pd, joint: elbow, kp: 10, kd: 1, target: {table: own.h5}}\n")
        # a binary STL tetrahedron for the MJCF mesh
        tris = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 0, 1), (1, 0, 0)),
                ((0, 0, 0), (0, 1, 0), (0, 0, 1)), ((1, 0, 0), (0, 0, 1), (0, 1, 0))]
        stl = b"\0" * 80 + struct.pack("<I", len(tris))
        for t in tris:
            stl += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *[0.1 * c for c in v]) for v in t) + b"\0\0"
        os.mkdir(self.path("meshes"))
        self.write("meshes/tet.stl", stl)
        self.write("body.xml", '<mujoco><body name="link" pos="0 0 0"><joint name="hinge" axis="0 1 0"/>'
                   '<geom type="capsule" size="0.02" fromto="0 0 0 0 0 -0.3" contype="0" conaffinity="0"/>'
                   '<geom type="mesh" mesh="tet" contype="0" conaffinity="0"/></body></mujoco>\n')
        self.write("robot.xml", '<mujoco model="m"><compiler meshdir="meshes"/><asset><mesh name="tet" file="tet.stl"/>'
                   '</asset><worldbody><include file="body.xml"/></worldbody></mujoco>\n')
        self.write("mj.yaml", "model: robot.xml\nsimulation: {t_end: 0.05}\n")
        # strippath: MuJoCo reads meshes/tet.stl for the file named elsewhere/tet.stl
        self.write("robot2.xml", '<mujoco model="m2"><compiler meshdir="meshes" strippath="true"/><asset>'
                   '<mesh name="tet" file="elsewhere/tet.stl"/></asset><worldbody><include file="body.xml"/></worldbody></mujoco>\n')
        self.write("mj2.yaml", "model: robot2.xml\nsimulation: {t_end: 0.05}\n")
        return {"arm.yaml": ["arm.urdf", "table.csv", "own.h5"], "mj.yaml": ["robot.xml", "body.xml", "meshes/tet.stl"],
                "mj2.yaml": ["robot2.xml", "meshes/tet.stl"]}

    def test_run_and_simulate_never_write_onto_what_the_scenario_read(self):
        """8 inputs of 3 scenes x (their name, a symlink to them) x (run -o --force, simulate(output=)): 32 cases"""
        for scene, inputs in self.scene_with_everything().items():
            for name in inputs:
                for alias in (name, "alias"):
                    if alias == "alias":
                        os.symlink(self.path(name), self.path("alias"))
                    before = digest(self.path(name))
                    for label, command in (("run --force", lambda o: run("run", self.path(scene), "-o", o, "-q", "--force")),
                                           ("simulate", lambda o: simulate(self.path(scene), o))):
                        with self.subTest(scene=scene, input=name, alias=alias, command=label):
                            self.assertRefused(command(self.path(alias)), r"the output is the input file .*" + name.split("/")[-1])
                            self.assertEqual(digest(self.path(name)), before)
                    if alias == "alias":
                        os.unlink(self.path("alias"))

    def test_identify_never_writes_onto_what_the_scenario_read(self):
        """identify -o --force onto the scene's URDF, CSV and run-file tables, the data, the MJCF files, include, mesh: 9 cases"""
        scenes = self.scene_with_everything()
        data = self.make_run("data.h5", self.path("arm.yaml"))
        for scene, inputs in scenes.items():
            for name in inputs + (["data.h5"] if scene == "arm.yaml" else []):
                with self.subTest(name):
                    before = digest(self.path(name))
                    r = run("identify", self.path(scene), "--data", data, "--parameters", "all", "-o", self.path(name),
                            "-q", "--force")
                    self.assertRefused(r, r"the output is the input file .*" + name.split("/")[-1])
                    self.assertEqual(digest(self.path(name)), before)

    def test_a_pickled_scenario_keeps_its_files(self):
        """a Scenario through pickle still knows its URDF and tables: simulate(output=) onto each refused (3 cases)"""
        self.scene_with_everything()
        code = ("import pickle, sys, soadyn\nsc = pickle.loads(pickle.dumps(soadyn.load_scenario(sys.argv[1])))\n"
                "try:\n    soadyn.simulate(sc, output=sys.argv[2], t_end=0.05)\n"
                "except soadyn.Error as e:\n    print(e, file=sys.stderr); sys.exit(2)\n")
        for name in ("arm.urdf", "table.csv", "own.h5"):
            with self.subTest(name):
                before = digest(self.path(name))
                r = subprocess.run([sys.executable, "-c", code, self.path("arm.yaml"), self.path(name)], capture_output=True,
                                   text=True, timeout=60, env=ENV)
                self.assertRefused(r, r"the output is the input file .*" + name)
                self.assertEqual(digest(self.path(name)), before)

    def test_a_pd_target_run_file_is_not_replaced_by_the_run(self):
        """{table: own.h5} with -o own.h5 and no --force: own.h5 is a soadyn run, and still never replaced"""
        self.scene_with_everything()
        before = digest(self.path("own.h5"))
        self.assertRefused(run("run", self.path("arm.yaml"), "-o", self.path("own.h5"), "-q"), r"the output is the input file")
        self.assertEqual(digest(self.path("own.h5")), before)


class Names(Base):
    BAD = {"../../escaped": r"cannot hold '/'", "a/b": r"cannot hold '/'", "..": r"cannot be empty, '\.' or '\.\.'",
           '"a\\x01b"': r"control characters", '"a\\\\b"': r"cannot hold '/' or '\\'", "x" * 300: r"at most 200 bytes",
           '""': r"name, got ''"}

    def test_names_that_are_not_a_file_name_are_refused(self):
        """7 names x (run without -o, Python load_scenario): file:line:column: name:, nothing written anywhere"""
        work = os.path.join(self.dir, "deep", "er")
        os.makedirs(work)
        with open(PENDULUM) as f:
            body = "".join(line for line in f if not line.startswith("name:"))
        for name, pattern in self.BAD.items():
            with self.subTest(name=name[:20]):
                scene = self.write("bad.yaml", f"# a scene\nname: {name}\n" + body)
                r = run("run", scene, "-q", "--t-end", "0.05", cwd=work)
                self.assertRefused(r, r"bad\.yaml:2:7: name: expected a .*" + pattern)
                load = subprocess.run([sys.executable, "-c", "import sys, soadyn\ntry:\n    soadyn.load_scenario(sys.argv[1])\n"
                                       "except soadyn.Error as e:\n    print(e, file=sys.stderr); sys.exit(2)\n", scene],
                                      capture_output=True, text=True, timeout=60, env=ENV)
                self.assertRefused(load, r"bad\.yaml:2:7: name: " + ".*" + pattern)
                found = [os.path.join(d, n) for d, _, ns in os.walk(self.dir) for n in ns if n != "bad.yaml"]
                self.assertEqual(found, [], "nothing written")

    def test_a_plain_name_still_names_the_default_output(self):
        with open(PENDULUM) as f:
            scene = self.write("ok.yaml", "name: my scene\n" + f.read().replace("name: double_pendulum\n", ""))
        r = run("run", scene, "-q", "--t-end", "0.05", cwd=self.dir)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(os.path.isfile(self.path("out/my scene.h5")))


class OutputSize(Base):
    def chain(self, n):
        bodies = "".join(f"  - {{name: b{k}, {'parent: b' + str(k - 1) + ', ' if k else ''}joint: {{type: revolute, axis: [1, 0, 0]}}, "
                         f"origin: {{xyz: [0, 0, -0.1]}}, mass: 1, com: [0, 0, -0.05], inertia: [0.01, 0.01, 0.01]}}\n"
                         for k in range(n))
        return f"name: chain\ngravity: [0, 0, -9.81]\nbodies:\n{bodies}"

    def test_sensitivities_count_against_the_limit_before_anything_is_written(self):
        """sensitivities (initial state; all parameters), frames: refused at 10M with exit 2, the folder untouched;
        the same run without them fits (so the refusal is theirs)"""
        # 10 bodies, 20001 rows: 31 doubles a row with --log state (4.7 MiB); the initial state's
        # sensitivities add 20 x 20 (+61 MiB), the parameters' 20 x 100, ten frames' poses 70 (+10.7 MiB)
        base = self.chain(10) + "simulation: {t_end: 0.1, output_dt: 5.0e-6, method: cvode-bdf"
        scenes = {"initial": base + ", sensitivities: {initial_state: true}}\n",
                  "parameters": base + ", sensitivities: {parameters: all}}\n",
                  "frames": base + "}\nlog: {frames: [" + ", ".join(f"b{k}" for k in range(10)) + "]}\n"}
        plain = self.write("plain.yaml", base + "}\n")
        for label, text in scenes.items():
            with self.subTest(label):
                scene = self.write(f"{label}.yaml", text)
                before = sorted(os.listdir(self.dir))
                r = run("run", scene, "-o", self.path("out/o.h5"), "--max-output-size", "10M", "--log", "state", timeout=20)
                self.assertRefused(r, r"o\.h5: the output would take .* more than --max-output-size 10M")
                self.assertEqual(sorted(os.listdir(self.dir)), before, "nothing written, no folder made")
        # the same rows without the sensitivities or frames fit
        r = run("run", plain, "-o", self.path("out/o.h5"), "--max-output-size", "10M", "--log", "state", "-q")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertLess(os.path.getsize(self.path("out/o.h5")), 10 << 20)


class SweepDir(Base):
    def sweep_file(self):
        return self.write("s.sweep.yaml", f"scenario: {PENDULUM}\nset: {{simulation.t_end: 0.02, simulation.output_dt: 0.01}}\n"
                                          "vary:\n  - {path: initial.q.theta1, uniform: [-1.0, 1.0], count: 3}\n")

    def sweep(self, out, *extra):
        return run("sweep", self.sweep_file(), "-o", out, "--scheduler", "serial", "-q", *extra, timeout=120)

    def test_a_foreign_results_file_is_refused_unless_forced(self):
        """a text file, an HDF5 file, a soadyn run file, a symlink to a file: refused with nothing written; --force replaces
        (a link: the link, never its target): 4 kinds x 2"""
        run_file = self.make_run("in.h5")
        for kind in ("text", "hdf5", "run", "link"):
            with self.subTest(kind):
                out = self.path(f"sw_{kind}")
                os.mkdir(out)
                results = os.path.join(out, "results.h5")
                victim = self.victim()
                if kind == "text":
                    shutil.copy(victim, results)
                elif kind == "hdf5":
                    with h5py.File(results, "w") as f:
                        f["data"] = [1.0, 2.0]
                elif kind == "run":
                    shutil.copy(run_file, results)
                else:
                    os.symlink(victim, results)
                before = digest(results)
                self.assertRefused(self.sweep(out), r"results\.h5: exists and is .*not a soadyn sweep's table")
                self.assertEqual(os.listdir(out), ["results.h5"], "nothing else written")
                self.assertEqual(digest(results), before)
                r = self.sweep(out, "--force")
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertFalse(os.path.islink(results))
                with h5py.File(results, "r") as f:
                    self.assertEqual(len(f["cases/case"]), 3)
                with open(victim, "rb") as f:
                    self.assertEqual(f.read(), PRECIOUS)
                # its own table is replaced without --force when the sweep runs again
                self.assertEqual(self.sweep(out).returncode, 0)

    def test_temporary_names_in_the_sweep_dir_are_never_written_through(self):
        """sweep.json.tmp, results.h5.tmp and a part's .tmp as symlinks to a file: the file untouched, the links removed"""
        out = self.path("sw")
        os.makedirs(os.path.join(out, "parts"))
        victim = self.victim()
        for name in ("sweep.json.tmp", "results.h5.tmp", "parts/cases-0000000-0000002-3.json.tmp"):
            os.symlink(victim, os.path.join(out, name))
        r = self.sweep(out)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(victim, "rb") as f:
            self.assertEqual(f.read(), PRECIOUS)
        left = [n for d, _, ns in os.walk(out) for n in ns if n.endswith(".tmp")]
        self.assertEqual(left, [])
        self.assertTrue(os.path.isfile(os.path.join(out, "sweep.json")) and not os.path.islink(os.path.join(out, "sweep.json")))


if __name__ == "__main__":
    unittest.main(verbosity=2)
