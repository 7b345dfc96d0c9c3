#!/usr/bin/python3
"""soadyn run with controllers and joint limits, as a user runs it: the Panda-like arm's fingers held
inside their travel (and sliding out of it with limits off, which the run then names), the limits'
events and the controllers' torques in the run file, torques saturated at the URDF's efforts, and a
computed-torque controller following a table exported from another run."""
import os
import subprocess
import tempfile
import unittest

import h5py
import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
SCENARIOS = os.path.join(os.environ.get("SOADYN_SOURCE_DIR", "."), "scenarios")


def run(*args):
    p = subprocess.run([SOADYN, "run", *args], capture_output=True, text=True, timeout=120)
    if p.returncode != 0:
        raise AssertionError(p.stderr)
    return p


class PandaGripper(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.out = os.path.join(cls.tmp.name, "panda.h5")
        cls.printed = run(os.path.join(SCENARIOS, "panda_gripper.yaml"), "-o", cls.out).stdout
        with h5py.File(cls.out) as f:
            cls.names = [n.decode() if isinstance(n, bytes) else n for n in f["model"].attrs["v_names"]]
            cls.q, cls.t = f["q"][:], f["time"][:]
            cls.control, cls.events = f["control"][:], f["events"][:]
            cls.lost = f["energy/impact_loss"][:]

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_fingers_stay_inside_their_travel_and_end_held_at_it(self):
        left, right = self.names.index("panda_finger_joint1"), self.names.index("panda_finger_joint2")
        for k in (left, right):
            self.assertGreaterEqual(self.q[:, k].min(), -1e-9)
            self.assertLessEqual(self.q[:, k].max(), 0.04 + 1e-9)
        # flung apart, pressed past their travel: held at the limits from the impact to the end
        self.assertAlmostEqual(self.q[-1, left], 0.04, delta=1e-9)
        self.assertAlmostEqual(self.q[-1, right], 0.0, delta=1e-9)
        held = self.t > 0.1
        self.assertLess(np.abs(self.q[held, left] - 0.04).max(), 1e-9)

    def test_events_in_the_run_file_and_on_stdout(self):
        dofs = sorted(int(d) for d in self.events[:, 1])
        self.assertEqual(dofs, [self.names.index("panda_finger_joint1"), self.names.index("panda_finger_joint2")])
        self.assertTrue(np.all(self.events[:, 5] == 0.0))  # restitution 0: stopped dead
        # the energy the impacts took, ½ m v² of each finger's relative motion through 𝓜: logged in L(t)
        self.assertAlmostEqual(self.lost[-1], self.events[:, 6].sum(), delta=1e-12)
        self.assertGreater(self.events[:, 6].min(), 0.0)
        self.assertIn("limit events           2 (", self.printed)

    def test_torques_saturate_at_the_urdf_efforts(self):
        effort = np.array([87, 87, 87, 87, 12, 12, 12, 20, 20], float)
        self.assertTrue(np.all(np.abs(self.control).max(axis=0) <= effort * (1 + 1e-12)))
        # the base joint's swing needs its torque: a real controller at work
        self.assertGreater(np.abs(self.control[:, 0]).max(), 1.0)
        # the base joint tracks its sine (computed torque, poles −10, −10) once the start's error decays
        late = self.t > 1.5
        self.assertLess(np.abs(self.q[late, 0] - 0.8 * np.sin(np.pi * self.t[late])).max(), 1e-3)

    def test_limits_off_slides_the_fingers_out_and_says_so(self):
        out = os.path.join(self.tmp.name, "off.h5")
        p = run(os.path.join(SCENARIOS, "panda_gripper.yaml"), "-o", out, "--limits", "off")
        self.assertIn("soadyn: warning: joints past their limits", p.stderr)
        self.assertIn("panda_finger_joint1", p.stderr)
        with h5py.File(out) as f:
            self.assertGreater(f["q"][:, 7].max(), 0.045)


class TableTarget(unittest.TestCase):
    def test_computed_torque_follows_a_table_exported_from_a_run(self):
        with tempfile.TemporaryDirectory() as d:
            swing = os.path.join(d, "swing.h5")
            run(os.path.join(SCENARIOS, "double_pendulum.yaml"), "-o", swing, "--t-end", "2", "--output-dt", "0.005")
            subprocess.run([SOADYN, "export", swing, "--csv", os.path.join(d, "swing.csv")], check=True, timeout=60)
            with open(os.path.join(SCENARIOS, "double_pendulum.yaml")) as f:
                text = f.read()
            with open(os.path.join(d, "follow.yaml"), "w") as f:
                f.write(text + "\ninputs:\n  controllers:\n    - {type: computed_torque, kp: 400, kd: 40, targets: swing.csv}\n")
            # the follower starts 0.1 rad off: computed torque (poles −20, −20) brings it onto the table
            follow = os.path.join(d, "follow.h5")
            run(os.path.join(d, "follow.yaml"), "-o", follow, "--t-end", "2", "--output-dt", "0.005", "--q", "1.1,-0.4")
            free = os.path.join(d, "free.h5")  # the same start without the controller
            run(os.path.join(SCENARIOS, "double_pendulum.yaml"), "-o", free, "--t-end", "2", "--output-dt", "0.005",
                "--q", "1.1,-0.4")
            with h5py.File(swing) as a, h5py.File(follow) as b, h5py.File(free) as c:
                t = a["time"][:]
                err, drift = np.abs(a["q"][:] - b["q"][:]).max(axis=1), np.abs(a["q"][:] - c["q"][:]).max(axis=1)
                self.assertAlmostEqual(err[0], 0.1, delta=1e-12)
                # the spline through 5 ms samples is good to ~1e-4 rad where the pendulum whips (q⁗ large)
                self.assertLess(err[t > 1.0].max(), 1e-3)
                self.assertGreater(drift[t > 1.0].max(), 0.05)

if __name__ == "__main__":
    unittest.main()
