#!/usr/bin/python3
"""soadyn identify as a user runs it: a run of tests/data/identify_arm.yaml (known parameters), the
scene with the forearm 30 % heavier and its inertia 30 % lower fitted back by least squares and by
Gauss-Newton (1e-6 relative), the fitted scene written and loaded back (its own fit moves nothing),
a URDF robot's fitted scene written in another directory (the urdf: path relative to it), and each
bad input refused with exit 2, one line naming the file or field, and nothing written (a scene
with enforced joint limits by either method: least squares would be biased)."""
import os
import re
import shutil
import subprocess
import tempfile
import unittest

SOADYN = os.environ.get("SOADYN", "build/soadyn")
SOURCE = os.environ.get("SOADYN_SOURCE_DIR", ".")
ARM = os.path.join(SOURCE, "tests", "data", "identify_arm.yaml")
ARM7 = os.path.join(SOURCE, "tests", "data", "arm7.urdf")

# the forearm's π in identify_arm.yaml: m, m c, inertia about the body origin (I_cm + m(|c|² − c cᵀ))
M, C = 1.0, (0.015, -0.01, 0.35)
I_CM = ((0.041, 0.0005, -0.001), (0.0005, 0.040, 0.0008), (-0.001, 0.0008, 0.006))


def truth():
    cc = sum(x * x for x in C)
    Io = [[I_CM[r][c] + M * ((cc if r == c else 0.0) - C[r] * C[c]) for c in range(3)] for r in range(3)]
    return {"forearm.m": M, "forearm.mcx": M * C[0], "forearm.mcy": M * C[1], "forearm.mcz": M * C[2],
            "forearm.Ixx": Io[0][0], "forearm.Ixy": Io[0][1], "forearm.Iyy": Io[1][1], "forearm.Ixz": Io[0][2],
            "forearm.Iyz": Io[1][2], "forearm.Izz": Io[2][2]}


def soadyn(*args):
    return subprocess.run([SOADYN, *map(str, args)], capture_output=True, text=True, timeout=600)


def table(stdout):
    """{parameter: (scene, fitted, standard error)} from the printed table"""
    out = {}
    for line in stdout.splitlines():
        m = re.match(r"^(\S+\.\w+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(kg.*)$", line)
        if m:
            out[m.group(1)] = tuple(float(m.group(k)) for k in (2, 3, 4))
    return out


class Identify(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.data = os.path.join(cls.dir, "run.h5")
        p = soadyn("run", ARM, "-o", cls.data, "-q")
        assert p.returncode == 0, p.stderr
        # the scene a user starts from: the forearm 30 % heavier, its inertia about the cm 30 % lower
        with open(ARM) as f:
            text = f.read()
        inertia = [[0.7 * x for x in row] for row in I_CM]
        cls.start = os.path.join(cls.dir, "start.yaml")
        with open(cls.start, "w") as f:
            f.write(text + f"inertial:\n  forearm: {{mass: 1.3, com: {list(C)}, inertia: {inertia}}}\n")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def check_recovered(self, stdout, tol):
        got = table(stdout)
        self.assertEqual(sorted(got), sorted(truth()))
        for name, value in truth().items():
            scene, fitted, _ = got[name]
            self.assertLessEqual(abs(fitted - value), tol * max(abs(value), 1e-3), (name, fitted, value))
        self.assertNotAlmostEqual(got["forearm.m"][0], M)  # the scene was off

    def test_least_squares_recovers_the_forearm_and_writes_a_scene_that_loads_it(self):
        out = os.path.join(self.dir, "fitted.yaml")
        p = soadyn("identify", self.start, "--data", self.data, "--parameters", "forearm", "-o", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("method       least-squares", p.stdout)
        self.assertIn("rank 10", p.stdout)
        self.check_recovered(p.stdout, 1e-6)
        with open(out) as f:
            self.assertTrue(f.readline().startswith("# fitted by soadyn identify"))
        # the fitted scene's own fit: already at the data, nothing moves
        again = soadyn("identify", out, "--data", self.data, "--parameters", "forearm")
        self.assertEqual(again.returncode, 0, again.stderr)
        for name, (scene, fitted, _) in table(again.stdout).items():
            self.assertAlmostEqual(scene, truth()[name], delta=1e-8 * max(1.0, abs(truth()[name])))
        self.assertRegex(again.stdout, r"RMS \S+e-1\d at the scene's values")
        # its own earlier output is replaced without --force
        p = soadyn("identify", self.start, "--data", self.data, "--parameters", "forearm", "-o", out, "-q")
        self.assertEqual(p.returncode, 0, p.stderr)

    def test_gauss_newton_on_the_trajectory(self):
        p = soadyn("identify", self.start, "--data", self.data, "--parameters", "forearm", "--method", "gauss-newton",
                   "--window", "0.05")
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("method       gauss-newton", p.stdout)
        self.check_recovered(p.stdout, 1e-6)

    def test_unidentifiable_parameters_are_named_not_fitted(self):
        p = soadyn("identify", ARM, "--data", self.data, "--parameters", "turret")
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("rank 1 ", p.stdout)
        lines = p.stdout.split("not identifiable from this data (held at the scene's values), 9 directions:\n")[1].split("\n")
        self.assertEqual([l.strip() for l in lines[:9]], ["turret." + n for n in
                                                          ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz")])
        got = table(p.stdout)
        for name in ("turret.m", "turret.Ixx"):
            self.assertEqual(got[name][0], got[name][1])  # held

    def test_a_urdf_robots_fitted_scene_elsewhere_loads_its_robot(self):
        run = os.path.join(self.dir, "arm7.h5")
        self.assertEqual(soadyn("run", ARM7, "-o", run, "--t-end", "1", "-q").returncode, 0)
        sub = os.path.join(self.dir, "sub", "deeper")
        os.makedirs(sub, exist_ok=True)
        out = os.path.join(sub, "arm7_fitted.yaml")
        p = soadyn("identify", ARM7, "--data", run, "--parameters", "all", "-o", out, "-q")
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(out) as f:
            text = f.read()
        self.assertIn("urdf: " + os.path.relpath(os.path.abspath(ARM7), sub), text)
        again = soadyn("identify", out, "--data", run, "--parameters", "all")
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertRegex(again.stdout, r"RMS \S+e-1\d at the scene's values")

    def test_plot_compares_the_fitted_run_with_the_logged_one(self):
        """tools/plot.py --compare (tools/figures.sh's identify_arm.png): the fitted scene's run stays
        on the logged one, the scene's own does not; a run compared with itself deviates by 0"""
        fitted, fitted_run = os.path.join(self.dir, "plot_fitted.yaml"), os.path.join(self.dir, "plot_fitted.h5")
        off_run = os.path.join(self.dir, "plot_off.h5")
        self.assertEqual(soadyn("identify", self.start, "--data", self.data, "--parameters", "forearm", "-o", fitted,
                                "-q").returncode, 0)
        for scene, out in ((fitted, fitted_run), (self.start, off_run)):
            self.assertEqual(soadyn("run", scene, "-o", out, "-q").returncode, 0)
        png, csv = os.path.join(self.dir, "plot.png"), os.path.join(self.dir, "plot.csv")
        p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "tools", "plot.py"), self.data, "--compare",
                            f"{off_run},{fitted_run},{self.data}", "-o", png, "--data", csv, "--bins", "10000"],
                           capture_output=True, text=True, timeout=300, env=dict(os.environ, MPLBACKEND="Agg"))
        self.assertEqual(p.returncode, 0, p.stderr)
        import numpy as np
        with open(csv) as f:
            header = f.readline().strip().split(",")
        table_ = np.loadtxt(csv, delimiter=",", skiprows=1)
        dev = {h.split(" − ")[0]: table_[:, k] for k, h in enumerate(header) if " − " in h}
        self.assertEqual(sorted(dev), ["plot_fitted", "plot_off", "run"])
        self.assertGreater(dev["plot_off"].max(), 1.0)      # rad: 30 % off drifts away
        self.assertLess(dev["plot_fitted"].max(), 1e-5)     # the fit stays on the data
        self.assertLessEqual(dev["run"].max(), 1e-17)       # itself: 0 (drawn at the log floor)
        for f in (fitted, fitted_run, off_run, png, csv):
            os.remove(f)

    def refused(self, args, message, out=None):
        before = sorted(os.listdir(self.dir))
        p = soadyn("identify", *args)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        line = p.stderr.strip()
        self.assertEqual(len(line.splitlines()), 1, line)
        self.assertIn(message, line)
        self.assertEqual(sorted(os.listdir(self.dir)), before, "nothing written")
        return line

    def test_bad_inputs_are_refused_with_nothing_written(self):
        out = os.path.join(self.dir, "never.yaml")
        base = ["--data", self.data, "-o", out]
        self.refused([ARM, *base, "--parameters", "forarm"], "no body named 'forarm'; did you mean 'forearm'?")
        other = os.path.join(self.dir, "pendulum.h5")
        self.assertEqual(soadyn("run", os.path.join(SOURCE, "scenarios", "double_pendulum.yaml"), "-o", other,
                                "--t-end", "0.1", "-q").returncode, 0)
        self.refused([ARM, "--data", other, "-o", out, "--parameters", "forearm"],
                     "pendulum.h5: /q: the run's joints (theta1, theta2) are not the scene's (theta1, theta2, theta3)")
        energy = os.path.join(self.dir, "energy.h5")
        self.assertEqual(soadyn("run", ARM, "-o", energy, "--t-end", "0.1", "--log", "energy", "-q").returncode, 0)
        self.refused([ARM, "--data", energy, "-o", out, "--parameters", "forearm"], "energy.h5: dataset /q is missing")
        notrun = os.path.join(self.dir, "notes.txt")
        with open(notrun, "w") as f:
            f.write("not a run\n")
        self.refused([ARM, "--data", notrun, "-o", out, "--parameters", "forearm"], "notes.txt: not a run file")
        self.refused([ARM, *base, "--parameters", "forearm", "--method", "newton"], "--method")
        # the fit with the upper arm too: its mass and m c_x cannot be seen, and held at the scene's
        # values while the rest move they make no rigid body: refused, the body named
        self.refused([self.start, *base, "--parameters", "upper_arm,forearm"], "the fit is no rigid body: body 'upper_arm'")
        for f in (notrun, other, energy):
            os.remove(f)

    def test_enforced_limits_are_refused_by_either_method(self):
        # the arm's forearm stopped at ±0.6 rad (limits: true): the run hits the stop, where a holding
        # force and impulses act that τ = Y π does not have; least squares (asked, or chosen by auto
        # for a run with /qdd) refuses as Gauss-Newton does, one line, exit 2, nothing written
        with open(ARM) as f:
            text = f.read().replace("simulation:\n", "simulation:\n  limits: true\n  restitution: 0.5\n")
        limited = os.path.join(self.dir, "limited.yaml")
        with open(limited, "w") as f:
            f.write(text + "limits: {theta3: [-0.6, 0.6]}\n")
        data = os.path.join(self.dir, "limited.h5")
        p = soadyn("run", limited, "-o", data, "--t-end", "2", "-q")
        self.assertEqual(p.returncode, 0, p.stderr)
        out = os.path.join(self.dir, "never.yaml")
        for method in ("least-squares", "auto"):
            line = self.refused([limited, "--data", data, "-o", out, "--parameters", "forearm", "--method", method],
                                "identify: least-squares: " + limited + ": the scene enforces joint limits (simulation: "
                                "limits: true)")
            self.assertIn("set limits: false", line)
        self.refused([limited, "--data", data, "-o", out, "--parameters", "forearm", "--method", "gauss-newton"],
                     "enforced joint limits")
        for f in (limited, data):
            os.remove(f)

    def test_outputs_that_are_not_its_own_are_refused(self):
        mine = os.path.join(self.dir, "mine.txt")
        with open(mine, "w") as f:
            f.write("someone's notes\n")
        self.refused([ARM, "--data", self.data, "--parameters", "forearm", "-o", mine],
                     "exists and is not a soadyn fitted scenario; refusing to replace it")
        with open(mine) as f:
            self.assertEqual(f.read(), "someone's notes\n")
        self.refused([self.start, "--data", self.data, "--parameters", "forearm", "-o", self.start],
                     "the output is the input file")
        p = soadyn("identify", ARM, "--data", self.data, "--parameters", "forearm", "-o", mine, "--force", "-q")
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(mine) as f:
            self.assertTrue(f.read().startswith("# fitted by soadyn identify"))
        os.remove(mine)


if __name__ == "__main__":
    unittest.main()
