#!/usr/bin/python3
"""What a refusal shows, through the soadyn executable on real files: a user's value is cut to its
first 60 bytes with its length (a 5 MB field, a sweep whose scenario is a file that is not one: the
file never printed back), control characters in YAML keys and values and in a CSV table's column
names shown as \\xHH (never raw to the terminal), and the refusals of a run's combinations (a start
beyond a joint limit, limits with a fixed-step method, sensitivities a run cannot differentiate,
an MJCF gravity of NaN) each naming the file, its line and the field, the other half given in the
file or on the command line.  Every refusal: exit 2, one
line on stderr, nothing on stdout."""
import os
import subprocess
import tempfile
import unittest

SOADYN = os.environ.get("SOADYN", "build/soadyn")
PYTHONPATH = os.environ.get("SOADYN_PYTHONPATH", os.path.join(os.path.dirname(os.path.abspath(SOADYN)), "python"))

ARM = """name: arm
gravity: [0, 0, -9.81]
bodies:
  - name: upper
    joint: {type: revolute, name: shoulder, axis: [0, 1, 0]}
    mass: 1.0
    com: [0, 0, 0.3]
    inertia: [0.01, 0.01, 0.001]
  - name: fore
    parent: upper
    joint: {type: revolute, name: elbow, axis: [0, 1, 0]}
    origin: {xyz: [0, 0, 0.6]}
    mass: 1.0
    com: [0, 0, 0.3]
    inertia: [0.01, 0.01, 0.001]
"""


class Messages(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, text, mode="w"):
        path = os.path.join(self.dir, name)
        with open(path, mode) as f:
            f.write(text)
        return path

    def refused(self, *args, env=None):
        """stderr's one line of a refused command (exit 2, nothing on stdout)"""
        p = subprocess.run([SOADYN, *args], capture_output=True, timeout=120, cwd=self.dir, env=env)
        self.assertEqual(p.returncode, 2, (args, p.stderr[:500]))
        self.assertEqual(p.stdout, b"", args)
        err = p.stderr.decode("utf-8")
        self.assertEqual(err.count("\n"), 1, err[:500])
        for c in range(32):
            if c != 10:
                self.assertNotIn(chr(c), err, f"control character {c:#x} in {err[:300]!r}")
        self.assertNotIn("\x7f", err)
        return err.strip()

    def test_a_long_value_is_cut_with_its_length(self):
        big = "x" * 5_000_000
        self.write("big.yaml", ARM + f"simulation: {{method: {big}}}\n")
        err = self.refused("inspect", "big.yaml")
        self.assertIn("big.yaml:16:", err)
        self.assertIn("… (5000000 bytes)", err)
        self.assertLess(len(err), 600)
        # an unknown key of 1000 bytes (YAML's longest implicit key)
        self.write("key.yaml", ARM + "k" * 1000 + ": 1\n")
        err = self.refused("inspect", "key.yaml")
        self.assertIn("unknown key 'kkkk", err)
        self.assertIn("… (1000 bytes)", err)
        self.assertLess(len(err), 800)

    def test_a_file_that_is_no_scenario_is_not_printed_back(self):
        secret = "root:x:0:0:" + "secret-content-" * 400 + "\nuser:x:1000:1000::/home/user:/bin/sh\n"
        self.write("passwd", secret)
        self.write("scene.yaml", secret)
        err = self.refused("inspect", "scene.yaml")
        self.assertIn("got plain text (", err)
        self.assertNotIn("secret-content", err)
        self.assertLess(len(err), 400)
        self.write("s.sweep.yaml", "scenario: passwd\nvary:\n  - {path: simulation.t_end, values: [1, 2]}\n")
        env = dict(os.environ, PYTHONPATH=PYTHONPATH)
        err = self.refused("sweep", "s.sweep.yaml", "-o", "out", "--scheduler", "serial", env=env)
        self.assertIn("s.sweep.yaml:1:11: scenario: ", err)
        self.assertNotIn("secret-content", err)
        self.assertLess(len(err), 600)
        self.assertFalse(os.path.exists(os.path.join(self.dir, "out", "results.h5")))

    def test_control_characters_are_escaped(self):
        self.write("key.yaml", ARM + "simulation: {\"t_\\e[31mend\\r\": 1}\n")
        err = self.refused("inspect", "key.yaml")
        self.assertIn("unknown key 't_\\x1b[31mend\\x0d'", err)
        self.write("value.yaml", ARM + "simulation: {method: \"rk\\e]0;title\\a4\"}\n")
        err = self.refused("inspect", "value.yaml")
        self.assertIn("\\x1b]0;title\\x074", err)
        # a CSV table's column names, listed when the asked column is not there
        self.write("t.csv", "t,sh\x1b[2Joulder,el\rbow\n0,0,0\n1,1,1\n")
        self.write("pd.yaml", ARM + "inputs:\n  controllers:\n    - {type: pd, joint: shoulder, kp: 1, kd: 1, "
                               "target: {table: t.csv, column: nope}}\n")
        err = self.refused("inspect", "pd.yaml")
        self.assertIn("pd.yaml:18:", err)
        self.assertIn("(it has sh\\x1b[2Joulder, el\\x0dbow)", err)
        # a 100 kB column name with an escape, named twice: cut and escaped
        name = "\x1b[5m" + "c" * 100_000
        self.write("t.csv", f"t,{name},{name}\n0,0,0\n1,1,1\n")
        err = self.refused("inspect", "pd.yaml")
        self.assertIn("t.csv:1: column '\\x1b[5mccc", err)
        self.assertIn("… (100004 bytes)' is named twice", err)
        self.assertLess(len(err), 600)

    def test_bad_prescribed_motion_is_refused_in_one_line(self):
        """prescribed: an unknown joint, a multi-DOF one, a table too short for q̈, an initial value
        that disagrees, limits enforced on it, a misspelt key: each at its file's line and field"""
        self.write("short.csv", "t,shoulder\n0,0\n1,0.5\n2,1\n")
        ball = ARM.replace("type: revolute, name: elbow, axis: [0, 1, 0]", "type: ball, name: elbow")
        cases = [
            (ARM + "prescribed: {wrist: 0.5}\n", "p.yaml:16:14: prescribed: no joint named 'wrist'"),
            (ball + "prescribed: {elbow: 0.5}\n", "p.yaml:16:14: prescribed: acts on 1-DOF joints"),
            (ARM + "prescribed: {shoulder: {table: short.csv}}\n",
             "p.yaml:16:32: prescribed.shoulder.table: "),
            (ARM + "initial: {q: {shoulder: 0.2}}\nprescribed: {shoulder: {slew: {from: 0, to: 1, duration: 2}}}\n",
             "p.yaml:16:25: initial.q.shoulder: joint 'shoulder' is prescribed (prescribed.shoulder), which starts it at 0, not 0.2"),
            (ARM + "limits: {shoulder: [-1, 1]}\nprescribed: {shoulder: 0.5}\nsimulation: {limits: true}\n",
             "p.yaml:17:24: prescribed: joint 'shoulder' has limits"),
            (ARM + "prescribed: {shoulder: {slew: {from: 0, to: 1, time: 2}}}\n",
             "p.yaml:16:48: prescribed.shoulder.slew: unknown key 'time'"),
        ]
        for text, want in cases:
            self.write("p.yaml", text)
            err = self.refused("run", "p.yaml", "-o", "out.h5")
            self.assertIn(want, err)
            self.assertFalse(os.path.exists(os.path.join(self.dir, "out.h5")))
        self.assertIn("rows; a prescribed motion's q̈ needs a spline through at least 4",
                      (self.write("p.yaml", cases[2][0]), self.refused("inspect", "p.yaml"))[1])

    def test_bad_loops_are_refused_in_one_line(self):
        """loops: an unknown body, an unknown type, a loop from a body to itself, an axis on a point
        loop, a loop no initial state closes, and a feature that does not take loops: each at its
        line and field, nothing written"""
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        with open(os.path.join(root, "scenarios", "four_bar.yaml")) as f:
            four = f.read()
        head = four[:four.index("loops:")]
        tail = four[four.index("initial:"):]
        loop = "loops:\n  - {type: hinge, a: coupler, at_a: [1.0, 0, 0], b: rocker, at_b: [0.8, 0, 0]}\n"
        cases = [
            (head + loop.replace("b: rocker", "b: rockr") + tail, "loops[0].b: no body or frame named 'rockr'"),
            (head + loop.replace("type: hinge", "type: slider") + tail, "loops[0].type: expected point, hinge, weld or distance"),
            (head + loop.replace("b: rocker", "b: coupler") + tail, "loops[0]: a and b are the same body"),
            (head + loop.replace("type: hinge", "type: point").replace("at_b: [0.8, 0, 0]", "at_b: [0.8, 0, 0], axis: [0, 0, 1]") + tail,
             "loops[0].axis: only a hinge has an axis"),
            (head + loop.replace("at_b: [0.8, 0, 0]", "at_b: [5.0, 0, 0]") + tail, "loops: the initial state cannot be closed on the loops"),
            (head + loop + tail.replace("method: cvode-adams", "method: symplectic-euler"),
             "loops: symplectic-euler (use rk4, implicit-midpoint or a CVODE method) is not available with closed loops yet"),
        ]
        for text, want in cases:
            self.write("l.yaml", text)
            err = self.refused("run", "l.yaml", "-o", "out.h5")
            self.assertIn(want, err)
            self.assertIn("l.yaml:", err)
            self.assertFalse(os.path.exists(os.path.join(self.dir, "out.h5")))

    def test_a_dead_point_stops_the_run_with_exit_3_naming_t_and_the_loop(self):
        """a parallelogram four-bar (crank = rocker, coupler = ground) turning at 2 rad/s from π/2
        reaches its change point, every link on the ground line, at t = π/4: the run stops there with
        exit 3 and one line naming the loop and t, its file keeping the rows before it (never NaN)"""
        text = """name: parallelogram
bodies:
  - name: crank
    joint: {type: revolute, name: crank, axis: [0, 0, 1]}
    mass: 1.0
    com: [0.15, 0, 0]
    inertia: [0.001, 0.0075, 0.0075]
  - name: coupler
    parent: crank
    joint: {type: revolute, name: coupler, axis: [0, 0, 1]}
    origin: {xyz: [0.3, 0, 0]}
    mass: 1.5
    com: [0.45, 0, 0]
    inertia: [0.001, 0.1, 0.1]
  - name: rocker
    joint: {type: revolute, name: rocker, axis: [0, 0, 1]}
    origin: {xyz: [0.9, 0, 0]}
    mass: 1.0
    com: [0.15, 0, 0]
    inertia: [0.001, 0.0075, 0.0075]
loops:
  - {name: closing, type: hinge, a: coupler, at_a: [0.9, 0, 0], b: rocker, at_b: [0.3, 0, 0]}
initial:
  q: {crank: 1.5707963267948966, coupler: -1.5707963267948966, rocker: 1.5707963267948966}
  qd: {crank: 2.0}
simulation: {t_end: 2.0, method: cvode-bdf, rtol: 1.0e-10, atol: 1.0e-12}
"""
        self.write("p.yaml", text)
        p = subprocess.run([SOADYN, "run", "p.yaml", "-o", "out.h5", "--quiet"], capture_output=True, timeout=120, cwd=self.dir)
        err = p.stderr.decode("utf-8")
        self.assertEqual(p.returncode, 3, err[:500])
        self.assertIn("closed loop 'closing' at a singular configuration (a dead point) at t = 0.78", err)
        self.assertNotIn("nan", err.lower())
        import h5py
        import numpy as np
        with h5py.File(os.path.join(self.dir, "out.h5"), "r") as f:
            t = f["time"][:]
            self.assertGreater(len(t), 10)
            self.assertLess(t[-1], np.pi / 4 + 1e-6)
            self.assertTrue(np.all(np.isfinite(f["/loops/force"][:])))

    def test_each_refused_combination_names_its_file_line_and_field(self):
        cases = [
            # a start beyond a joint's limit: at initial.q.J
            ("start.yaml", "limits: {elbow: [-1, 1]}\ninitial: {q: {elbow: 2}}\nsimulation: {limits: true}\n",
             "start.yaml:17:22: initial.q.elbow: initial state: joint 'elbow' starts at 2, beyond its upper limit 1"),
            # … at limits.J when the start is the default
            ("start0.yaml", "limits: {elbow: [0.5, 1]}\nsimulation: {limits: true}\n",
             "start0.yaml:16:17: limits.elbow: initial state: joint 'elbow' starts at 0, beyond its lower limit 0.5"),
            ("fixed.yaml", "limits: {elbow: [-1, 1]}\nsimulation: {method: rk4, limits: true}\n",
             "fixed.yaml:17:35: simulation.limits: true needs an integrator that locates events"),
            ("sens_fixed.yaml", "simulation: {method: rk4, sensitivities: {initial_state: true}}\n",
             "sens_fixed.yaml:16:42: simulation.sensitivities: need a CVODE method"),
            ("sens_pd.yaml", "simulation: {sensitivities: {parameters: all}}\ninputs:\n  controllers:\n"
                             "    - {type: pd, joint: elbow, kp: 1, kd: 1, target: 0}\n",
             "sens_pd.yaml:16:29: simulation.sensitivities: a run with a controller (inputs.controllers)"),
            ("sens_limits.yaml", "limits: {elbow: [-1, 1]}\nsimulation: {limits: true, sensitivities: {initial_state: true}}\n",
             "sens_limits.yaml:17:43: simulation.sensitivities: enforced joint limits"),
        ]
        for name, tail, expect in cases:
            self.write(name, ARM + tail)
            err = self.refused("run", name, "-o", "out.h5")
            self.assertIn(expect, err, name)
            self.assertFalse(os.path.exists(os.path.join(self.dir, "out.h5")))
        # the other half given on the command line: refused at the file's line all the same, and a
        # command line that mends the combination runs
        self.write("cvode.yaml", ARM + "limits: {elbow: [-1, 1]}\nsimulation: {limits: true, t_end: 0.01}\n")
        err = self.refused("run", "cvode.yaml", "--method", "rk4", "-o", "out.h5")
        self.assertIn("cvode.yaml:17:22: simulation.limits: true needs an integrator that locates events", err)
        p = subprocess.run([SOADYN, "run", "fixed.yaml", "--method", "cvode-bdf", "--t-end", "0.01", "-o", "out.h5", "-q"],
                           capture_output=True, timeout=120, cwd=self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        # an MJCF file's gravity of NaN: the file, its line, the attribute
        if os.environ.get("SOADYN_MJCF", "ON") != "ON":
            return
        self.write("g.xml", '<mujoco>\n  <option gravity="0 0 nan"/>\n  <worldbody><body><joint/>'
                            '<geom type="sphere" size="0.1" contype="0" conaffinity="0"/></body></worldbody>\n</mujoco>\n')
        self.write("g.yaml", "model: g.xml\n")
        self.assertIn("g.xml:2: option: attribute 'gravity': expected finite numbers", self.refused("inspect", "g.xml"))
        err = self.refused("inspect", "g.yaml")
        self.assertIn("g.yaml:1:8: model: ", err)
        self.assertIn("g.xml:2: option: attribute 'gravity'", err)


if __name__ == "__main__":
    unittest.main()
