#!/usr/bin/python3
"""MJCF files through the soadyn executable, as a user runs it in a folder of their own: a `nan`
attribute with the working folder's MUJOCO_LOG.TXT a link to a victim file (the victim unchanged,
no MUJOCO_LOG.TXT made, stdout empty on the refusal and JSON on a valid model, exit 2 and one line
naming file:line), each dropped value named on stderr, the generated frame names, and identify on
an MJCF body with several joints: the fit of every body with a mass, written as a YAML that loads
and fits again, and a massless frame named to it refused in one line."""
import json
import os
import re
import subprocess
import tempfile
import unittest

SOADYN = os.environ.get("SOADYN", "build/soadyn")

GEOM = '<geom type="sphere" size="0.05" contype="0" conaffinity="0"/>'

NAN_MODEL = f"""<mujoco>
  <worldbody>
    <body name="a" pos="nan 0 1">
      <joint name="j" type="hinge"/>
      {GEOM}
    </body>
  </worldbody>
</mujoco>
"""

# upper has two joints (its frame for x is generated: upper.x), fore one; all driven
ARM = f"""<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="upper" pos="0 0 0.1">
      <joint name="x" axis="1 0 0"/>
      <joint name="y" axis="0 1 0" pos="0 0 0.05"/>
      <inertial pos="0.02 -0.01 0.2" mass="2" fullinertia="0.05 0.048 0.006 0.001 -0.002 0.0005"/>
      <body name="fore" pos="0 0 0.4">
        <joint name="z" axis="0 1 0"/>
        <inertial pos="0.01 0.01 0.15" mass="1" diaginertia="0.02 0.021 0.004"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

SCENE = """model: arm.xml
simulation: {t_end: 1.0, output_dt: 0.005}
initial: {q: {x: 0.3, y: -0.2, z: 0.4}, qd: {x: 1.0}}
inputs:
  torques:
    - {joint: x, amplitude: 2.0, frequency: 1.3}
    - {joint: y, amplitude: 1.5, frequency: 0.7, phase: 0.5}
    - {joint: z, amplitude: 1.0, frequency: 2.1}
"""


def soadyn(*args, cwd=None):
    return subprocess.run([SOADYN, *map(str, args)], capture_output=True, text=True, timeout=120, cwd=cwd)


class Folder(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, text):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path


class MuJoCoWritesNothing(Folder):
    def test_a_nan_is_refused_and_the_log_link_is_left_alone(self):
        victim = self.write("victim.txt", "someone else's file\n")
        os.symlink("victim.txt", os.path.join(self.dir, "MUJOCO_LOG.TXT"))
        self.write("nan.xml", NAN_MODEL)
        self.write("ok.xml", NAN_MODEL.replace("nan 0 1", "0 0 1"))
        for args in (["inspect", "nan.xml", "--json"], ["inspect", "nan.xml"], ["run", "nan.xml", "-o", "out.h5"]):
            p = soadyn(*args, cwd=self.dir)
            self.assertEqual(p.returncode, 2, (args, p.stderr))
            self.assertEqual(p.stdout, "", args)
            lines = p.stderr.strip().split("\n")
            self.assertEqual(len(lines), 1, p.stderr)
            self.assertIn("nan.xml:3: body: attribute 'pos': expected finite numbers", lines[0])
            self.assertFalse(os.path.exists(os.path.join(self.dir, "out.h5")))
        # a valid model in the same folder: JSON on stdout, exit 0
        p = soadyn("inspect", "ok.xml", "--json", cwd=self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertEqual(json.loads(p.stdout)["nv"], 1)
        with open(victim) as f:
            self.assertEqual(f.read(), "someone else's file\n")
        self.assertTrue(os.path.islink(os.path.join(self.dir, "MUJOCO_LOG.TXT")))
        self.assertEqual(sorted(os.listdir(self.dir)), ["MUJOCO_LOG.TXT", "nan.xml", "ok.xml", "victim.txt"])

    def test_without_a_log_file_none_is_made(self):
        self.write("nan.xml", NAN_MODEL.replace('pos="nan 0 1"', 'pos="0 0 1"').replace('type="hinge"', 'type="hinge" stiffness="NaN"'))
        p = soadyn("inspect", "nan.xml", "--json", cwd=self.dir)
        self.assertEqual(p.returncode, 2)
        self.assertEqual(p.stdout, "")
        self.assertIn("nan.xml:4: joint: attribute 'stiffness': expected finite numbers, got 'NaN'", p.stderr)
        self.assertEqual(os.listdir(self.dir), ["nan.xml"])


class DroppedValues(Folder):
    def test_each_is_named_on_stderr_and_invalid_ones_refused(self):
        self.write("m.xml", f"""<mujoco><option density="1.2"/><worldbody>
  <body name="a"><joint name="h" frictionloss="0.4"/>{GEOM}
    <body name="b" pos="0 0 0.2"><joint name="s" type="ball" damping="0.3"/>{GEOM}</body></body>
</worldbody></mujoco>
""")
        p = soadyn("inspect", "m.xml", "--json", cwd=self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        json.loads(p.stdout)
        self.assertIn("ignored: ", p.stderr)
        for what in ("1 joint frictionloss (dry friction)", "1 ball- or free-joint damping", "<option density> (fluid forces)"):
            self.assertIn(what, p.stderr)
        for attr, value, line in (("damping", "-1", 2), ("stiffness", "nan", 2)):
            self.write("bad.xml", f'<mujoco><worldbody>\n<body><joint {attr}="{value}"/>{GEOM}</body>\n</worldbody></mujoco>\n')
            p = soadyn("inspect", "bad.xml", cwd=self.dir)
            self.assertEqual(p.returncode, 2)
            self.assertIn(f"bad.xml:{line}: joint: attribute '{attr}': expected", p.stderr)


class IdentifyOnAMultiJointBody(Folder):
    def test_the_fit_is_written_and_loads(self):
        self.write("arm.xml", ARM)
        scene = self.write("scene.yaml", SCENE)
        p = soadyn("inspect", "scene.yaml", "--json", cwd=self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        p = soadyn("run", "scene.yaml", "-o", "run.h5", "-q", cwd=self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        # a massless frame named: refused in one line, nothing written
        p = soadyn("identify", "scene.yaml", "--data", "run.h5", "--parameters", "upper.x", "-o", "fit.yaml", cwd=self.dir)
        self.assertEqual(p.returncode, 2)
        self.assertIn("body 'upper.x' is massless in the scene", p.stderr)
        self.assertEqual(len(p.stderr.strip().split("\n")), 1)
        self.assertFalse(os.path.exists(os.path.join(self.dir, "fit.yaml")))
        # every body with a mass, fitted from a scene that starts 30 % off, written, loaded, fitted again
        with open(scene, "a") as f:
            f.write("inertial:\n  fore: {mass: 1.3, com: [0.01, 0.01, 0.15], inertia: [0.014, 0.0147, 0.0028]}\n")
        for bodies in ("all", "fore", "upper,fore"):
            p_fit = soadyn("identify", "scene.yaml", "--data", "run.h5", "--parameters", bodies, "-o", "fit.yaml", cwd=self.dir)
            self.assertEqual(p_fit.returncode, 0, (bodies, p_fit.stderr))
            self.assertNotIn("upper.x.", p_fit.stdout)  # the frame is no parameter
            p = soadyn("inspect", "fit.yaml", "--json", cwd=self.dir)
            self.assertEqual(p.returncode, 0, (bodies, p.stderr))
            # the written scene is the fit: at its values the run's torques are met (the start's
            # residual is not), whatever the bodies fitted (a child's mass alone is not identifiable
            # beside its parent's parameters)
            again = soadyn("identify", "fit.yaml", "--data", "run.h5", "--parameters", bodies, cwd=self.dir)
            self.assertEqual(again.returncode, 0, again.stderr)
            rms = re.search(r"residual\s+RMS (\S+) at the scene's values, (\S+) fitted", again.stdout)
            self.assertLess(float(rms.group(1)), 1e-9, again.stdout)
            start = re.search(r"residual\s+RMS (\S+) at the scene's values", p_fit.stdout)
            self.assertGreater(float(start.group(1)), 1e-3, p_fit.stdout)
            if bodies == "fore":  # alone it is: its 1 kg back
                row = next(l for l in again.stdout.splitlines() if l.startswith("fore.m "))
                self.assertLess(abs(float(row.split()[1]) - 1.0), 1e-6, row)


if __name__ == "__main__":
    unittest.main()
