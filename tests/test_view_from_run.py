#!/usr/bin/python3
"""soadyn view reads nothing but the run file: a run whose target table moved, changed or became a
FIFO is viewed as it ran; a crafted run file whose scenario names /etc/passwd as its robot or its
table shows nothing of it (refused in one line, or drawn from what the file holds).  Real runs,
real files, the real command."""
import os
import shutil
import subprocess
import tempfile
import unittest

import h5py
import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SECRET = "/etc/passwd"

SCENE = """name: tracked
bodies:
  - name: link
    joint: {type: revolute, name: hinge, axis: [1, 0, 0]}
    mass: 1.0
    com: [0, 0, -0.5]
    inertia: [0.1, 0.1, 0.01]
gravity: [0, 0, -9.81]
simulation: {t_end: 0.3, output_dt: 0.01}
inputs:
  controllers:
    - {type: pd, joint: hinge, kp: 20, kd: 2, target: {table: target.csv, column: hinge}}
"""


def set_text(f, name, text):
    """a fixed-length string dataset, as layout 5 writes them"""
    if name in f:
        del f[name]
    data = text.encode()
    f.create_dataset(name, data=np.array(data, dtype=f"S{max(1, len(data))}"))


class ViewFromRun(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_view_run_")
        with open(self.path("scene.yaml"), "w") as f:
            f.write(SCENE)
        with open(self.path("target.csv"), "w") as f:
            f.write("time [s],hinge [rad]\n0,0\n1,0.5\n")
        r = self.soadyn("run", self.path("scene.yaml"), "-o", self.path("run.h5"), "-q")
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(SECRET) as f:
            self.secret_lines = [line.strip() for line in f if len(line.strip()) > 8][:5]

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def soadyn(self, *args):
        return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=60)

    def assertNothingOf(self, secret_holder, r):
        for line in self.secret_lines:
            self.assertNotIn(line, r.stdout + r.stderr)
        page = self.path("v.html")
        if os.path.exists(page):
            with open(page, encoding="utf-8") as f:
                text = f.read()
            for line in self.secret_lines:
                self.assertNotIn(line, text, secret_holder)

    def test_a_run_whose_table_moved_changed_or_is_a_fifo_is_viewed(self):
        for change in ("moved", "changed", "fifo"):
            if os.path.exists(self.path("target.csv")):
                os.remove(self.path("target.csv"))
            if change == "changed":
                with open(self.path("target.csv"), "w") as f:
                    f.write("not a table\n")
            elif change == "fifo":
                os.mkfifo(self.path("target.csv"))
            r = self.soadyn("view", self.path("run.h5"), "-o", self.path("v.html"), "-q", "--force")
            self.assertEqual(r.returncode, 0, (change, r.stderr))
            self.assertGreater(os.path.getsize(self.path("v.html")), 10000, change)
            os.remove(self.path("v.html"))

    def test_a_crafted_run_naming_etc_passwd_shows_nothing_of_it(self):
        cases = {
            # the robot: a layout-5 file without /robot names one on disk: refused, not read
            "robot": (f"urdf: {SECRET}\n", True, 2),
            # a table target: inputs are not parsed by view; the page is drawn from the bodies
            "table": (SCENE.replace("target.csv", SECRET), False, 0),
            # an MJCF model: the same as a URDF
            "model": (f"model: {SECRET}\n", True, 2),
        }
        for what, (text, drop_robot, code) in cases.items():
            crafted = self.path(f"crafted_{what}.h5")
            shutil.copy(self.path("run.h5"), crafted)
            with h5py.File(crafted, "r+") as f:
                set_text(f, "scenario", text)
                if drop_robot and "robot" in f:
                    del f["robot"]
            r = self.soadyn("view", crafted, "-o", self.path("v.html"), "-q", "--force")
            self.assertEqual(r.returncode, code, (what, r.stderr))
            if code:
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
                self.assertIn(crafted, r.stderr)
            self.assertNothingOf(what, r)
            if os.path.exists(self.path("v.html")):
                os.remove(self.path("v.html"))


if __name__ == "__main__":
    unittest.main(verbosity=2)
