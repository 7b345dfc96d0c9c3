#!/usr/bin/python3
"""soadyn view reads nothing but the run file (a URDF's mesh files aside): a run whose target table
moved, changed or became a FIFO is viewed as it ran; a crafted run file whose scenario names
/etc/passwd as its robot or its table shows nothing of it (refused in one line, or drawn from what
the file holds), nor does a URDF naming it (or a link to it, or a device) as a mesh.  Real runs,
real files, the real command.  An MJCF model's <include>s and meshes are stored in the run file
(/model_files): a run viewed after its include changed and its mesh was deleted draws the run's
model, and a run file written before they were stored is refused in one line."""
import json
import os
import re
import shutil
import struct
import subprocess
import tempfile
import unittest

import h5py
import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
ROOT = os.environ.get("SOADYN_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
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
    @staticmethod
    def secret_lines_of():
        with open(SECRET) as f:
            return [line.strip() for line in f if len(line.strip()) > 8][:5]

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


# an MJCF model: the main file, an <include> with the bodies and a mesh asset (a binary STL tetrahedron)
MJCF_MAIN = ('<mujoco model="m"><compiler meshdir="meshes"/><asset><mesh name="tet" file="tet.stl"/></asset>'
             '<worldbody><include file="body.xml"/></worldbody></mujoco>\n')
MJCF_BODY = ('<mujoco><body name="upper" pos="0 0 1"><joint name="shoulder" axis="0 1 0"/>'
             '<geom type="capsule" size="0.02" fromto="0 0 0 0 0 -0.3" contype="0" conaffinity="0"/>'
             '<body name="lower" pos="0 0 -0.3"><joint name="elbow" axis="0 1 0"/>'
             '<geom type="mesh" mesh="tet" contype="0" conaffinity="0"/></body></body></mujoco>\n')
# the include changed after the run: another body position, another axis, a third joint
MJCF_BODY_CHANGED = ('<mujoco><body name="upper" pos="0 0 2"><joint name="shoulder" axis="1 0 0"/>'
                     '<geom type="capsule" size="0.02" fromto="0 0 0 0 0 -0.3" contype="0" conaffinity="0"/>'
                     '<body name="lower" pos="0 0 -0.7"><joint name="elbow" axis="1 0 0"/>'
                     '<geom type="sphere" size="0.1" contype="0" conaffinity="0"/>'
                     '<body name="extra" pos="0 0 -0.2"><joint name="wrist" axis="1 0 0"/>'
                     '<geom type="sphere" size="0.05" contype="0" conaffinity="0"/></body></body></body></mujoco>\n')


def tetrahedron_stl():
    tris = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 0, 1), (1, 0, 0)),
            ((0, 0, 0), (0, 1, 0), (0, 0, 1)), ((1, 0, 0), (0, 0, 1), (0, 1, 0))]
    stl = b"\0" * 80 + struct.pack("<I", len(tris))
    for t in tris:
        stl += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *[0.1 * c for c in v]) for v in t) + b"\0\0"
    return stl


def mesh_block(path, k):
    """the base64 text of the page's mesh file k (view.cpp writes each in a block of its own)"""
    with open(path, encoding="utf-8") as f:
        return re.search(rf'<script type="text/plain" id="soadyn-mesh-{k}">(.*?)</script>', f.read(), re.S).group(1)


def page_data(path):
    """the JSON block the page embeds (view.cpp): the model as the page draws it"""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    m = re.search(r'<script type="application/json" id="soadyn-run">(.*?)</script>', text, re.S)
    return json.loads(m.group(1))


class MjcfViewFromRun(unittest.TestCase):
    """`soadyn run model.xml` and a scenario whose model: is that file: the MJCF's files stored,
    the view compiled from them alone"""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_view_mjcf_")
        os.mkdir(self.path("meshes"))
        with open(self.path("meshes/tet.stl"), "wb") as f:
            f.write(tetrahedron_stl())
        self.write("model.xml", MJCF_MAIN)
        self.write("body.xml", MJCF_BODY)
        self.write("scene.yaml", "model: model.xml\nsimulation: {t_end: 0.2, output_dt: 0.01}\n")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def write(self, name, text):
        with open(self.path(name), "w") as f:
            f.write(text)

    def soadyn(self, *args):
        return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=120)

    def run_and_view(self, source, run, page):
        r = self.soadyn("run", self.path(source), "-o", self.path(run), "-q", "--t-end", "0.2")
        self.assertEqual(r.returncode, 0, r.stderr)
        r = self.soadyn("view", self.path(run), "-o", self.path(page), "-q")
        self.assertEqual(r.returncode, 0, r.stderr)
        return page_data(self.path(page))

    def test_the_run_s_model_files_are_viewed_after_the_include_changed_and_the_mesh_went(self):
        for source in ("model.xml", "scene.yaml"):
            with self.subTest(source=source):
                self.write("body.xml", MJCF_BODY)
                with open(self.path("meshes/tet.stl"), "wb") as f:
                    f.write(tetrahedron_stl())
                run, before_page, after_page = f"{source}.h5", f"{source}.before.html", f"{source}.after.html"
                before = self.run_and_view(source, run, before_page)
                # the file holds every file MuJoCo was handed: the main text, the include, the mesh
                with h5py.File(self.path(run), "r") as f:
                    g = f["model_files"]
                    stored = {os.path.basename(g[str(k)].attrs["name"].decode()): bytes(g[str(k)][()])
                              for k in range(int(g.attrs["count"]))}
                    self.assertEqual(g[str(0)].dtype, np.uint8)
                self.assertEqual(stored["body.xml"], MJCF_BODY.encode())
                self.assertEqual(stored["tet.stl"], tetrahedron_stl())
                self.assertEqual(len(stored), 3, list(stored))
                self.assertEqual([b["joint"] for b in before["bodies"]], ["shoulder", "elbow"])
                # the include changed (a body moved, the axes turned, a third joint), the mesh deleted
                self.write("body.xml", MJCF_BODY_CHANGED)
                os.remove(self.path("meshes/tet.stl"))
                trace = self.path("view.strace")
                strace = ["strace", "-f", "-qq", "-e", "trace=%file", "-o", trace] if shutil.which("strace") else []
                r = subprocess.run([*strace, SOADYN, "view", self.path(run), "-o", self.path(after_page), "-q"],
                                   capture_output=True, text=True, timeout=120)
                self.assertEqual(r.returncode, 0, r.stderr)
                if strace:  # no model file is opened, nor even looked at, by name
                    with open(trace) as f:
                        calls = f.read()
                    for name in ("model.xml", "body.xml", "meshes/tet.stl", "meshes", "scene.yaml"):
                        self.assertNotIn('"' + self.path(name) + '"', calls, name)
                    self.assertNotIn("body.xml", calls)
                    self.assertNotIn("tet.stl", calls)
                after = page_data(self.path(after_page))
                # the run's model, drawn as before: the same bodies, axes, placements, shapes
                self.assertEqual(after["nq"], 2)
                self.assertEqual(after["bodies"], before["bodies"])
                self.assertEqual([b["axis"] for b in after["bodies"]], [[0, 1, 0], [0, 1, 0]])
                self.assertEqual(after["frames"]["pose"], before["frames"]["pose"])
                self.assertEqual(after["world_visuals"], before["world_visuals"])
                self.assertEqual(sum(b["meshes"] for b in after["bodies"]), 1)  # the mesh geom, still the run's
                # and drawn: the tetrahedron as MuJoCo compiled it from the stored file, in the page
                self.assertEqual(after["meshes"], before["meshes"])
                self.assertEqual([(m["format"], m["vertices"], m["triangles"], m["error"]) for m in after["meshes"]],
                                 [("arrays", 4, 4, None)])
                self.assertEqual(mesh_block(self.path(after_page), 0), mesh_block(self.path(before_page), 0))
                # nothing of the disk's files: the changed include would have given three joints
                self.assertNotIn("wrist", json.dumps(after))

    def test_a_run_file_from_before_the_files_were_stored_is_refused_in_one_line(self):
        for source in ("model.xml", "scene.yaml"):
            with self.subTest(source=source):
                run = f"old_{source}.h5"
                r = self.soadyn("run", self.path(source), "-o", self.path(run), "-q", "--t-end", "0.1")
                self.assertEqual(r.returncode, 0, r.stderr)
                with h5py.File(self.path(run), "r+") as f:
                    del f["model_files"]
                r = self.soadyn("view", self.path(run), "-o", self.path("old.html"), "-q", "--force")
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
                self.assertIn("written before the run file stored the MJCF's files; soadyn view reads nothing but the "
                              "run file", r.stderr)
                self.assertFalse(os.path.exists(self.path("old.html")))

    def test_an_old_run_of_an_mjcf_without_includes_or_assets_views_from_its_text(self):
        self.write("plain.xml", '<mujoco model="p"><worldbody><body name="b" pos="0 0 1"><joint name="j" axis="0 1 0"/>'
                   '<geom type="sphere" size="0.1" pos="0 0 -0.5" contype="0" conaffinity="0"/></body></worldbody>'
                   '</mujoco>\n')
        r = self.soadyn("run", self.path("plain.xml"), "-o", self.path("plain.h5"), "-q", "--t-end", "0.1")
        self.assertEqual(r.returncode, 0, r.stderr)
        with h5py.File(self.path("plain.h5"), "r+") as f:
            del f["model_files"]
        # the file on disk changed too: the page is the stored text's (one joint), not the disk's
        self.write("plain.xml", MJCF_MAIN)
        r = self.soadyn("view", self.path("plain.h5"), "-o", self.path("plain.html"), "-q")
        self.assertEqual(r.returncode, 0, r.stderr)
        data = page_data(self.path("plain.html"))
        self.assertEqual([b["joint"] for b in data["bodies"]], ["j"])


class UrdfMeshFiles(unittest.TestCase):
    """A URDF run's mesh files are not in the run file: soadyn view reads them from the disk when it
    writes the page, as input files (regular files only, of a mesh format), so a crafted URDF naming
    /etc/passwd, a link to it named .stl, or a device, puts nothing of them in the page"""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="soadyn_view_urdf_meshes_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def test_a_urdf_naming_etc_passwd_or_a_device_as_meshes_shows_nothing_of_them(self):
        os.symlink(SECRET, self.path("passwd.stl"))
        os.symlink(SECRET, self.path("passwd.dae"))
        os.symlink("/dev/zero", self.path("zero.stl"))
        names = [SECRET, "file://" + SECRET, "passwd.stl", "passwd.dae", "zero.stl", "package://etc/passwd.obj"]
        visuals = "".join(f'<visual><geometry><mesh filename="{n}"/></geometry></visual>' for n in names)
        with open(self.path("r.urdf"), "w") as f:
            f.write('<robot name="r"><link name="base"/><link name="l"><inertial><mass value="1"/><inertia ixx="0.1" '
                    f'iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>{visuals}</link><joint name="j" '
                    'type="continuous"><parent link="base"/><child link="l"/><axis xyz="1 0 0"/></joint></robot>\n')
        r = subprocess.run([SOADYN, "run", self.path("r.urdf"), "-o", self.path("r.h5"), "-q", "--t-end", "0.1"],
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        r = subprocess.run([SOADYN, "view", self.path("r.h5"), "-o", self.path("v.html"), "-q"],
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        notes = r.stderr.splitlines()
        # one per file (/etc/passwd named twice is one), each drawn as its body's default shape
        self.assertEqual(len(notes), 5, r.stderr)
        for line in notes:
            self.assertTrue(line.startswith("soadyn: note: ") and "drawn as its body's default shape" in line, line)
        for reason in ('a file without an extension', 'not an STL file', 'not a Collada file', 'a character device',
                       "no package folder 'etc'"):
            self.assertIn(reason, r.stderr)
        with open(self.path("v.html"), encoding="utf-8") as f:
            page = f.read()
        for line in ViewFromRun.secret_lines_of():
            self.assertNotIn(line, page)
        self.assertNotIn('id="soadyn-mesh-', page)  # no file's bytes in it
        self.assertEqual([m["error"] is not None for m in page_data(self.path("v.html"))["meshes"]], [True] * 5)


if __name__ == "__main__":
    unittest.main(verbosity=2)
