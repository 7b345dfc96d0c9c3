#!/usr/bin/python3
"""soadyn inspect from the command line: the JSON for the four scenario files against the note's
closed forms, the equations of motion it prints, and clear refusals (exit status 2) of bad input;
q̈ by its three routes is in test_cli_routes.py, which imports the helpers here."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

SOADYN = os.environ.get("SOADYN", "build/soadyn")
SCENARIOS = os.path.join(os.environ.get("SOADYN_SOURCE_DIR", "."), "scenarios")


def run(*args):
    return subprocess.run([SOADYN, *args], capture_output=True, text=True, timeout=60)


def inspect(*args):
    p = run("inspect", *args, "--json")
    if p.returncode != 0:
        raise AssertionError(p.stderr)
    lines = [l for l in p.stdout.splitlines() if l.strip()]
    assert len(lines) == 1, "exactly one JSON object on stdout"
    return json.loads(lines[0])


def skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def rot(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = skew(a)
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def quat(w, x, y, z):
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class ScenarioMassMatrices(unittest.TestCase):
    """The parameters below are the ones stated in scenarios/*.yaml."""
    rng = np.random.default_rng(5)

    def assertClose(self, got, expected, tol=1e-12):
        got, expected = np.asarray(got), np.asarray(expected)
        scale = max(1.0, np.abs(expected).max())
        self.assertLessEqual(np.abs(got - expected).max(), tol * scale, f"\n{got}\nvs\n{expected}")

    def check_eom(self, out):
        M, b, qdd, tau = (np.asarray(out[k]) for k in ("M", "bias", "qdd", "tau"))
        self.assertClose(M @ qdd + b, tau, 1e-10)
        self.assertTrue(np.all(np.linalg.eigvalsh(M) > 0))

    def test_pendulum_on_cart(self):
        for _ in range(20):
            x, th = self.rng.uniform(-3, 3, 2)
            out = inspect(f"{SCENARIOS}/pendulum_on_cart.yaml", "--q", f"{x!r},{th!r}", "--qd", "0.3,-1.2")
            m1, m2, L, Izz = 2.0, 1.0, 1.0, 0.0834
            self.assertClose(out["M"], [[m1 + m2, m2 * L * np.cos(th)], [m2 * L * np.cos(th), Izz + m2 * L * L]])
            self.assertEqual(out["joints"], ["x", "theta"])
            self.check_eom(out)

    def test_double_pendulum(self):
        for _ in range(20):
            t1, t2 = self.rng.uniform(-3, 3, 2)
            out = inspect(f"{SCENARIOS}/double_pendulum.yaml", "--q", f"{t1!r},{t2!r}")
            m, l1, c, J = 1.0, 1.0, 0.5, 0.0834
            M11 = 2 * J + m * c * c + m * (l1 * l1 + c * c + 2 * l1 * c * np.cos(t2))
            M12 = J + m * (c * c + l1 * c * np.cos(t2))
            self.assertClose(out["M"], [[M11, M12], [M12, J + m * c * c]])
            self.check_eom(out)

    def test_three_link_arm(self):
        # (P7) with the hinge axis read as C_1 e_x (see tests/algorithm/test_mass_matrix.cpp)
        ex, ez = np.eye(3)[0], np.eye(3)[2]
        m = [5.0, 2.0, 1.0]
        Ib = [np.diag([0.05, 0.05, 0.04]), np.diag([0.107, 0.107, 0.002]), np.diag([0.041, 0.041, 0.001])]
        com = [np.array([0, 0, 0.1]), np.array([0, 0, 0.4]), np.array([0, 0, 0.35])]
        d2, d3 = np.array([0, 0, 0.2]), np.array([0, 0, 0.8])
        for _ in range(20):
            q = self.rng.uniform(-3, 3, 3)
            R1 = rot(ez, q[0]); R2 = R1 @ rot(ex, q[1]); R3 = R2 @ rot(ex, q[2])
            R = [R1, R2, R3]
            eta = [np.zeros(3), R1 @ d2, R1 @ d2 + R2 @ d3]
            s = [R[j] @ com[j] for j in range(3)]
            r = [eta[j] + s[j] for j in range(3)]
            I = [R[j] @ Ib[j] @ R[j].T for j in range(3)]
            e = R1 @ ex
            S = lambda v: skew(v)
            E2 = S(eta[1])
            A11 = sum(I[j] - m[j] * S(r[j]) @ S(r[j]) for j in range(3))
            A12 = sum(I[j] - m[j] * S(r[j]) @ (S(r[j]) - E2) for j in (1, 2))
            A22 = sum(I[j] - m[j] * (S(r[j]) - E2) @ (S(r[j]) - E2) for j in (1, 2))
            S3 = S(s[2])
            M = np.array([
                [ez @ A11 @ ez, ez @ A12 @ e, ez @ (I[2] - m[2] * S(r[2]) @ S3) @ e],
                [0, e @ A22 @ e, e @ (I[2] - m[2] * (S(r[2]) - E2) @ S3) @ e],
                [0, 0, e @ (I[2] - m[2] * S3 @ S3) @ e]])
            M = np.triu(M) + np.triu(M, 1).T
            out = inspect(f"{SCENARIOS}/three_link_arm.yaml", "--q", ",".join(repr(float(v)) for v in q))
            self.assertClose(out["M"], M)
            self.check_eom(out)

    def test_satellite_two_arrays(self):
        ex = np.eye(3)[0]
        mb, ma = 500.0, 20.0
        Ib, Ia = np.diag([400.0, 350.0, 300.0]), np.diag([15.01, 3.76, 18.75])
        for _ in range(10):
            pos = self.rng.uniform(-5, 5, 3)
            qu = self.rng.normal(size=4); qu /= np.linalg.norm(qu)
            a2, a3 = self.rng.uniform(-3, 3, 2)
            q = [*pos, *qu, a2, a3]
            out = inspect(f"{SCENARIOS}/satellite_two_arrays.yaml", "--q", ",".join(repr(float(v)) for v in q),
                          "--qd", "0.01,0.02,-0.03,0.1,0.2,0.3,0.5,-0.4")
            R1 = quat(*qu)
            e = R1 @ ex
            R = [R1, R1 @ rot(ex, a2), R1 @ rot(ex, a3)]
            d = [np.zeros(3), R1 @ [0, 1.0, 0], R1 @ [0, -1.0, 0]]
            s = [np.zeros(3), R[1] @ [0, 2.0, 0], R[2] @ [0, -2.0, 0]]
            mass = [mb, ma, ma]
            I = [R[0] @ Ib @ R[0].T, R[1] @ Ia @ R[1].T, R[2] @ Ia @ R[2].T]
            r = [d[j] + s[j] for j in range(3)]  # from eta_1
            mbar = sum(mass)
            c = sum(mass[j] * r[j] for j in range(3)) / mbar
            M = np.zeros((8, 8))
            M[:3, :3] = sum(I[j] - mass[j] * skew(r[j]) @ skew(r[j]) for j in range(3))
            M[:3, 3:6] = mbar * skew(c)
            M[3:6, :3] = -mbar * skew(c)
            M[3:6, 3:6] = mbar * np.eye(3)
            for j in (1, 2):
                k = 5 + j
                M[:3, k] = (I[j] - mass[j] * skew(r[j]) @ skew(s[j])) @ e
                M[3:6, k] = -mass[j] * skew(s[j]) @ e
                M[k, :3] = e @ (I[j] - mass[j] * skew(s[j]) @ skew(r[j]))
                M[k, 3:6] = e @ (mass[j] * skew(s[j]))
                M[k, k] = e @ (I[j] - mass[j] * skew(s[j]) @ skew(s[j])) @ e
            self.assertClose(out["M"], M)
            self.check_eom(out)
            self.assertEqual(out["nq"], 9)
            self.assertEqual(out["nv"], 8)
            self.assertEqual(out["potential_energy"], 0.0)

    def test_initial_state_and_json_fields(self):
        out = inspect(f"{SCENARIOS}/double_pendulum.yaml")
        self.assertEqual(out["q"], [1.2, -0.5])
        for k in ("joints", "nq", "nv", "q", "qd", "gravity", "M", "bias", "qdd", "kinetic_energy",
                  "potential_energy", "momentum"):
            self.assertIn(k, out)
        self.assertEqual(set(out["momentum"]), {"linear", "angular"})

    def test_tau_and_methods(self):
        for method in ("dense", "sparse", "aba", "on"):  # "on": the O(N) route's old word, printed as aba
            out = inspect(f"{SCENARIOS}/three_link_arm.yaml", "--tau", "1,-2,0.5", "--qd", "0.3,-0.1,2",
                          "--method", method)
            self.assertEqual(out["method"], "aba" if method == "on" else method)
            self.check_eom(out)
            self.assertEqual(out["tau"], [1, -2, 0.5])

    def test_gravity_override_and_energy(self):
        out = inspect(f"{SCENARIOS}/pendulum_on_cart.yaml", "--gravity", "0,-1,0", "--q", "0,0", "--qd", "0,2")
        self.assertEqual(out["gravity"], [0, -1, 0])
        # V = m2 g L (1 - cos) - m2 g L at theta = 0: the pendulum cm at y = -1 -> V = -1 * 1 * 1
        self.assertAlmostEqual(out["potential_energy"], -1.0, places=14)
        self.assertAlmostEqual(out["kinetic_energy"], 0.5 * (0.0834 + 1.0) * 4, places=12)

    def test_negative_values_in_both_forms(self):
        a = inspect(f"{SCENARIOS}/double_pendulum.yaml", "--q", "-0.5,1")
        b = inspect(f"{SCENARIOS}/double_pendulum.yaml", "--q=-0.5,1")
        self.assertEqual(a["q"], [-0.5, 1])
        self.assertEqual(a, b)

    def test_urdf_model(self):
        urdf = """<?xml version="1.0"?>
<robot name="pend">
  <link name="world"/>
  <link name="bob">
    <inertial><origin xyz="0 0 -1"/><mass value="2"/>
      <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="hinge" type="continuous">
    <parent link="world"/><child link="bob"/><axis xyz="1 0 0"/>
  </joint>
</robot>"""
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "pend.urdf")
            with open(path, "w") as f:
                f.write(urdf)
            out = inspect(path, "--q", "0.3")
            self.assertEqual(out["gravity"], [0, 0, -9.81])
            self.assertAlmostEqual(out["M"][0][0], 0.1 + 2 * 1.0, places=14)
            self.assertAlmostEqual(out["bias"][0], 2 * 9.81 * np.sin(0.3), places=12)
            # a massless root cannot float
            p = run("inspect", path, "--free-root")
            self.assertEqual(p.returncode, 2)
            self.assertIn("pend.urdf:3: link 'world': inertial: expected mass properties for a free root", p.stderr)
            with open(path, "w") as f:
                f.write(urdf.replace('<link name="world"/>', '<link name="world"><inertial><mass value="3"/>'
                                     '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'))
            free = inspect(path, "--free-root")
            self.assertEqual((free["nq"], free["nv"]), (8, 7))
            self.assertEqual(free["q"][:7], [0, 0, 0, 1, 0, 0, 0])
            # floating: total mass 5 in the translational block
            self.assertAlmostEqual(free["M"][3][3], 5.0, places=14)
            # run takes the same model options as inspect: the free root falls under gravity
            # (z = −g t²/2), and view rebuilds the free-root model from the log
            import h5py
            out = os.path.join(d, "free.h5")
            p = run("run", path, "--free-root", "--t-end", "0.5", "--method", "RK4", "--dt", "1e-3", "-q", "-o", out)
            self.assertEqual(p.returncode, 0, p.stderr)
            with h5py.File(out, "r") as f:
                self.assertEqual(f["q"].shape[1], 8)
                self.assertLess(abs(f["q"][-1, 2] + 9.81 * 0.5 ** 2 / 2), 1e-9)
                method = f["solver"].attrs["method"]
                self.assertEqual(method.decode() if isinstance(method, bytes) else str(method), "rk4")
            p = run("view", out, "-o", os.path.join(d, "free.html"), "-q")
            self.assertEqual(p.returncode, 0, p.stderr)
            # --method is matched whatever its case; an unknown one is named
            self.assertEqual(run("inspect", path, "--method", "Dense").returncode, 0)
            p = run("run", path, "--method", "rk5", "-o", os.path.join(d, "x.h5"))
            self.assertEqual(p.returncode, 2)
            self.assertIn("rk5", p.stderr)


class BadInput(unittest.TestCase):
    def refused(self, *args, expect):
        p = run(*args)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn(expect, p.stderr)
        self.assertEqual(len([l for l in p.stderr.splitlines() if l.strip()]), 1, p.stderr)
        return p.stderr

    def test_junk_and_wrong_lengths(self):
        f = f"{SCENARIOS}/double_pendulum.yaml"
        self.refused("inspect", f, "--q", "1,abc", expect="--q: item 2: expected a finite number, got 'abc'")
        self.refused("inspect", f, "--q", "1,2,3", expect="--q: expected 2 numbers, got 3")
        self.refused("inspect", f, "--qd", "1", expect="--qd: expected 2 numbers, got 1")
        self.refused("inspect", f, "--tau", "1,nan", expect="--tau: item 2: expected a finite number")
        self.refused("inspect", f, "--q", "1,", expect="--q")
        self.refused("inspect", f, "--gravity", "0,0", expect="--gravity: expected 3 numbers, got 2")
        self.refused("inspect", f"{SCENARIOS}/satellite_two_arrays.yaml", "--q", "0,0,0,2,0,0,0,0,0",
                     expect="expected a unit quaternion")

    def test_files(self):
        self.refused("inspect", "/nonexistent.yaml", expect="/nonexistent.yaml: cannot open the file")
        with tempfile.TemporaryDirectory() as d:
            empty = os.path.join(d, "empty.yaml")
            open(empty, "w").close()
            self.refused("inspect", empty, expect="the file is empty")
            bad = os.path.join(d, "bad.yaml")
            with open(bad, "w") as f:
                f.write("bodies:\n  - name: a\n    joint: {type: revolute, axis: [0, 0, 1]}\n    mass: -1\n")
            self.refused("inspect", bad, expect="bad.yaml:4:11: body 'a'.mass: expected a positive mass")
            self.refused("inspect", d, expect="is a directory")
            binary = os.path.join(d, "binary.yaml")
            with open(binary, "wb") as f:
                f.write(b"\x00\x01binary")
            self.refused("inspect", binary, expect="a binary file, expected text")

    def test_inertias_breaking_the_triangle_inequality(self):
        # a CAD export rounded 2.5 % past the triangle inequality on two links: one warning naming
        # both; strict refuses naming both; balance loads them made physical
        urdf = os.path.join(os.environ.get("SOADYN_SOURCE_DIR", "."), "tests/data/urdf/rounded_inertias.urdf")
        p = run("inspect", urdf, "--json")
        self.assertEqual(p.returncode, 0, p.stderr)
        warnings = [l for l in p.stderr.splitlines() if l.strip()]
        self.assertEqual(len(warnings), 1, p.stderr)
        self.assertIn("warning", warnings[0])
        self.assertIn("'ankle_motor' [8.000000013e-05 0.0001599999999 0.000246] (+2.50 %), 'camera'", warnings[0])
        err = self.refused("inspect", urdf, "--inertia-check", "strict", expect="rounded_inertias.urdf:21: link 'ankle_motor': inertia")
        self.assertIn("'camera' [0.002 0.003 0.00512] (+2.40 %)", err)
        with tempfile.TemporaryDirectory() as d:
            p = run("run", urdf, "--inertia-check", "balance", "--t-end", "0.01", "-o", os.path.join(d, "r.h5"))
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("balanced 2 inertias", p.stderr)
        self.refused("inspect", urdf, "--inertia-check", "balanse", expect="--inertia-check")

    def test_run_options(self):
        f = f"{SCENARIOS}/double_pendulum.yaml"
        for opt in ("--dt", "--rtol", "--atol", "--t-end", "--output-dt"):
            self.refused("run", f, opt, "-1", expect=f"{opt}: expected a positive number, got '-1'")
        self.refused("run", f, "--method", "rk5", expect="got 'rk5'; did you mean 'rk4'?")
        # a mistyped option, command or choice gets the nearest name; case is ignored in choices
        self.refused("run", f, "--tend", "5", expect="'--tend' is not an option of soadyn run; did you mean '--t-end'?")
        self.refused("run", f, "--methd=euler", expect="did you mean '--method'?")
        self.refused("inspct", f, expect="'inspct' is not a soadyn command; did you mean 'inspect'?")
        self.refused("export", "x.h5", "--cvs", "a.csv", expect="did you mean '--csv'?")
        self.refused("run", f, "--jacobian", "analytik", expect="did you mean 'analytic'?")
        with tempfile.TemporaryDirectory() as d:
            p = run("run", f, "--jacobian", "DQ", "--method", "CVODE-BDF", "--t-end", "0.01", "-q", "-o", os.path.join(d, "r.h5"))
            self.assertEqual(p.returncode, 0, p.stderr)

    def test_options(self):
        self.refused("inspect", f"{SCENARIOS}/double_pendulum.yaml", "--method", "fast", expect="--method")
        p = run("inspect")
        self.assertEqual(p.returncode, 2)
        p = run()
        self.assertEqual(p.returncode, 2)

    def test_help(self):
        for args in (["--help"], ["inspect", "--help"]):
            p = run(*args)
            self.assertEqual(p.returncode, 0)
            self.assertIn("inspect", p.stdout)
        self.assertIn("--free-root", run("inspect", "--help").stdout)


class RunLog(unittest.TestCase):
    """soadyn run: its state options, its log groups, and body poses that agree with inspect."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.dir.cleanup()

    def run_ok(self, *args):
        p = run("run", *args)
        self.assertEqual(p.returncode, 0, p.stderr)
        return p

    def test_body_poses_match_inspect_at_sampled_states(self):
        import h5py
        for scene in ("satellite_two_arrays", "heavy_top", "three_link_arm", "pendulum_on_cart", "spherical_pendulum",
                      "driven_pendulum", "screw_lift"):
            out = os.path.join(self.dir.name, scene + ".h5")
            self.run_ok(f"{SCENARIOS}/{scene}.yaml", "--t-end", "1", "-q", "-o", out)
            with h5py.File(out, "r") as f:
                q, qd = f["q"][:], f["qd"][:]
                names = [n.decode() for n in f["model"].attrs["body_names"]]  # fixed-length: bytes
                self.assertEqual(list(f["bodies/names"].asstr()[:]), names)
                poses = {k: f["bodies/" + k][:] for k in ("position", "orientation", "com")}
            self.assertEqual(poses["position"].shape, (len(q), len(names), 3))
            self.assertEqual(poses["orientation"].shape, (len(q), len(names), 4))
            for row in (0, len(q) // 2, len(q) - 1):
                got = inspect(f"{SCENARIOS}/{scene}.yaml", "--q", ",".join(repr(float(x)) for x in q[row]),
                              "--qd", ",".join(repr(float(x)) for x in qd[row]))
                self.assertEqual([b["name"] for b in got["bodies"]], names)
                for i, b in enumerate(got["bodies"]):
                    for k in ("position", "orientation", "com"):
                        np.testing.assert_allclose(poses[k][row, i], b[k], rtol=0, atol=1e-12,
                                                   err_msg=f"{scene} row {row} body {b['name']} {k}")

    def test_initial_state_and_gravity_options(self):
        import h5py
        out = os.path.join(self.dir.name, "dp.h5")
        self.run_ok(f"{SCENARIOS}/double_pendulum.yaml", "--q", "-0.25,0.5", "--qd", "1,-2", "--gravity", "0,0,-1",
                    "--t-end", "0.5", "-q", "-o", out)
        with h5py.File(out, "r") as f:
            self.assertEqual(list(f["q"][0]), [-0.25, 0.5])
            self.assertEqual(list(f["qd"][0]), [1.0, -2.0])
            self.assertEqual(list(f["model"].attrs["gravity"]), [0.0, 0.0, -1.0])
            E = f["energy/total"][:]
        ref = inspect(f"{SCENARIOS}/double_pendulum.yaml", "--q", "-0.25,0.5", "--qd", "1,-2", "--gravity", "0,0,-1")
        self.assertAlmostEqual(E[0], ref["kinetic_energy"] + ref["potential_energy"], places=12)
        # the same refusals as inspect's
        f = f"{SCENARIOS}/double_pendulum.yaml"
        BadInput.refused(self, "run", f, "--q", "1,2,3", expect="--q: expected 2 numbers, got 3")
        BadInput.refused(self, "run", f"{SCENARIOS}/satellite_two_arrays.yaml", "--q", "0,0,0,2,0,0,0,0,0",
                         expect="expected a unit quaternion")
        BadInput.refused(self, "run", f, "--gravity", "0,0", expect="--gravity: expected 3 numbers, got 2")

    def test_log_groups(self):
        import h5py
        out = os.path.join(self.dir.name, "lean.h5")
        self.run_ok(f"{SCENARIOS}/three_link_arm.yaml", "--log", "energy,state", "--t-end", "0.1", "-q", "-o", out)
        with h5py.File(out, "r") as f:
            self.assertEqual(f.attrs["log_groups"].decode(), "state,energy")
            self.assertEqual(f["samples"].shape[1], 1 + 3 + 3 + 3 + 5)
            self.assertEqual(sorted(f), ["energy", "model", "q", "qd", "qdd", "samples", "scenario", "solver", "time"])
        out = os.path.join(self.dir.name, "bodies.h5")
        self.run_ok(f"{SCENARIOS}/three_link_arm.yaml", "--log", "bodies", "--t-end", "0.1", "-q", "-o", out)
        with h5py.File(out, "r") as f:
            self.assertEqual(f["samples"].shape[1], 1 + 30)
            self.assertNotIn("q", f)
        BadInput.refused(self, "run", f"{SCENARIOS}/three_link_arm.yaml", "--log", "state,poses", "-o", out,
                         expect="--log: expected a comma-separated list of state, energy, momentum, bodies (or all); "
                                "got 'poses' in 'state,poses'")

    def test_help_and_figures(self):
        p = run("run", "--help")
        self.assertEqual(p.returncode, 0)
        for text in ("MODEL", ".urdf", "--q", "--qd", "--gravity", "--log"):
            self.assertIn(text, p.stdout)
        out = os.path.join(self.dir.name, "a.h5")
        p = self.run_ok(f"{SCENARIOS}/double_pendulum.yaml", "--rtol", "1e-7", "--atol", "1e-9", "--t-end", "0.2", "-o", out)
        self.assertIn("(rtol 1e-07, atol 1e-09)", p.stdout)
        self.assertRegex(p.stdout, r"CPU time +[0-9.]+(e-?[0-9]+)? s\n")
        self.assertRegex(p.stdout, r"energy balance error +[0-9.]+(e-?[0-9]+)? \(final; max over the run")


if __name__ == "__main__":
    unittest.main(verbosity=2)
