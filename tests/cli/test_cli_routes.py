#!/usr/bin/python3
"""soadyn inspect's forward dynamics from the command line: q̈ by its three routes (dense Cholesky,
tree-sparse LᵀDL, O(N) articulated body) against each other and against q̈ = 𝓜⁻¹(τ − bias) from a
Newton–Euler reference written here from the scenarios' geometry (itself checked against the
note's Examples 1 and 2).  The closed-form 𝓜 of the same scenarios and the refusals are in
test_cli.py, whose helpers this file imports."""
import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_cli as cli  # noqa: E402  (the module, so its test cases do not run twice)


# The four scenarios as stated in scenarios/*.yaml: per body (parent, joint, axis, origin,
# mass, com, principal inertia), and gravity.
MECHANISMS = {
    "pendulum_on_cart": ([(-1, "prismatic", [1, 0, 0], [0, 0, 0], 2.0, [0, 0, 0], [0.05, 0.08, 0.1]),
                          (0, "revolute", [0, 0, 1], [0, 0, 0], 1.0, [0, -1.0, 0], [0.0834, 0.001, 0.0834])],
                         [0, -9.81, 0]),
    "double_pendulum": ([(-1, "revolute", [1, 0, 0], [0, 0, 0], 1.0, [0, 0, -0.5], [0.0834, 0.0834, 0.001]),
                         (0, "revolute", [1, 0, 0], [0, 0, -1.0], 1.0, [0, 0, -0.5], [0.0834, 0.0834, 0.001])],
                        [0, 0, -9.81]),
    "three_link_arm": ([(-1, "revolute", [0, 0, 1], [0, 0, 0], 5.0, [0, 0, 0.1], [0.05, 0.05, 0.04]),
                        (0, "revolute", [1, 0, 0], [0, 0, 0.2], 2.0, [0, 0, 0.4], [0.107, 0.107, 0.002]),
                        (1, "revolute", [1, 0, 0], [0, 0, 0.8], 1.0, [0, 0, 0.35], [0.041, 0.041, 0.001])],
                       [0, 0, -9.81]),
    "satellite_two_arrays": ([(-1, "free", None, None, 500.0, [0, 0, 0], [400.0, 350.0, 300.0]),
                              (0, "revolute", [1, 0, 0], [0, 1.0, 0], 20.0, [0, 2.0, 0], [15.01, 3.76, 18.75]),
                              (0, "revolute", [1, 0, 0], [0, -1.0, 0], 20.0, [0, -2.0, 0], [15.01, 3.76, 18.75])],
                             [0, 0, 0]),
}


def body_motion(mech, q, v):
    """Every body's C_j, inertia about its cm, ω_j and ṙ_j (inertial), by a forward pass written
    here from the geometry: children turn with their parent, hinges about C_parent axis."""
    out, iq, iv = [], 0, 0
    for parent, joint, axis, origin, m, com, inertia in mech[0]:
        if parent < 0:
            Rp, eta_p, wp, etad_p = np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3)
        else:
            Rp, eta_p, wp, etad_p = out[parent]["frame"]
        if joint == "free":  # q = [η, quaternion w x y z], v = [ω, η̇]
            R, eta = cli.quat(*q[iq + 3:iq + 7]), np.asarray(q[iq:iq + 3], float)
            w, etad = np.asarray(v[iv:iv + 3], float), np.asarray(v[iv + 3:iv + 6], float)
            iq, iv = iq + 7, iv + 6
        else:
            g = Rp @ (np.asarray(axis, float) / np.linalg.norm(axis))
            d = Rp @ np.asarray(origin, float) + (g * q[iq] if joint == "prismatic" else 0)
            eta, etad = eta_p + d, etad_p + np.cross(wp, d)
            if joint == "revolute":
                R, w = Rp @ cli.rot(axis, q[iq]), wp + g * v[iv]
            else:
                R, w, etad = Rp, wp, etad + g * v[iv]
            iq, iv = iq + 1, iv + 1
        s = R @ np.asarray(com, float)
        out.append({"frame": (R, eta, w, etad), "m": m, "I": R @ np.diag(inertia) @ R.T,
                    "w": w, "rd": etad + np.cross(w, s)})
    return out


def advance(mech, q, v, t):
    """q ⊕ t v: angles and positions move linearly, a free root's attitude turns about the constant ω."""
    q, k, j = np.array(q, float), 0, 0
    for _, joint, *_ in mech[0]:
        if joint == "free":
            w = np.asarray(v[j:j + 3], float)
            q[k:k + 3] += t * np.asarray(v[j + 3:j + 6], float)
            phi = np.linalg.norm(w) * t
            a = w / np.linalg.norm(w) if np.linalg.norm(w) > 0 else np.zeros(3)
            p = np.array([np.cos(phi / 2), *(np.sin(phi / 2) * a)])
            r = q[k + 3:k + 7]
            q[k + 3:k + 7] = [p[0] * r[0] - p[1:] @ r[1:], *(p[0] * r[1:] + r[0] * p[1:] + np.cross(p[1:], r[1:]))]
            k, j = k + 7, j + 6
        else:
            q[k] += t * v[j]
            k, j = k + 1, j + 1
    return q


def newton_euler(mech, q, v):
    """𝓜 and bias by virtual power: bias_k = Σ_j ∂ω_j/∂v_k · (I ω̇ + ω × I ω) + ∂ṙ_j/∂v_k · m (r̈ − g),
    with ω̇ and r̈ by central differences along q ⊕ t v at constant v (q̈ = 0)."""
    h, nv = 1e-5, len(v)
    now, plus, minus = (body_motion(mech, advance(mech, q, v, t), v) for t in (0, h, -h))
    cols = [body_motion(mech, q, np.eye(nv)[k]) for k in range(nv)]
    gravity = np.asarray(mech[1], float)
    M, bias = np.zeros((nv, nv)), np.zeros(nv)
    for j, b in enumerate(now):
        wdot = (plus[j]["w"] - minus[j]["w"]) / (2 * h)
        rdd = (plus[j]["rd"] - minus[j]["rd"]) / (2 * h)
        n = b["I"] @ wdot + np.cross(b["w"], b["I"] @ b["w"])
        f = b["m"] * (rdd - gravity)
        for k in range(nv):
            ck = cols[k][j]
            bias[k] += ck["w"] @ n + ck["rd"] @ f
            for l in range(nv):
                M[k, l] += ck["w"] @ b["I"] @ cols[l][j]["w"] + b["m"] * ck["rd"] @ cols[l][j]["rd"]
    return M, bias


class ForwardDynamicsRoutes(unittest.TestCase):
    """q̈ from the three routes (dense Cholesky, tree-sparse LᵀDL, O(N) articulated body) agree with
    each other and with q̈ = 𝓜⁻¹(τ − bias) from the Python references: 𝓜 in the note's closed
    form (test_cli.py's ScenarioMassMatrices) and by Newton–Euler, bias by Newton–Euler."""
    rng = np.random.default_rng(11)

    def close(self, got, expected, tol, what):
        got, expected = np.asarray(got, float), np.asarray(expected, float)
        err = np.abs(got - expected).max() / max(1.0, np.abs(expected).max())
        self.assertLessEqual(err, tol, f"{what}:\n{got}\nvs\n{expected}")

    def state(self, name, nv):
        if name == "satellite_two_arrays":
            qu = self.rng.normal(size=4)
            q = [*self.rng.uniform(-5, 5, 3), *(qu / np.linalg.norm(qu)), *self.rng.uniform(-3, 3, 2)]
            return np.array(q), self.rng.uniform(-1, 1, nv) * [0.3, 0.3, 0.3, 1, 1, 1, 1, 1]
        return self.rng.uniform(-3, 3, nv), self.rng.uniform(-2, 2, nv)

    def test_routes_against_each_other_and_python(self):
        for name, mech in MECHANISMS.items():
            nv = sum(6 if b[1] == "free" else 1 for b in mech[0])
            for _ in range(4):
                q, qd = self.state(name, nv)
                tau = self.rng.uniform(-5, 5, nv) * (100 if name == "satellite_two_arrays" else 1)
                M_ne, bias_ne = newton_euler(mech, q, qd)
                args = ["--q", ",".join(repr(float(x)) for x in q), "--qd", ",".join(repr(float(x)) for x in qd),
                        "--tau", ",".join(repr(float(x)) for x in tau)]
                outs = {m: cli.inspect(f"{cli.SCENARIOS}/{name}.yaml", *args, "--method", m) for m in ("dense", "sparse", "aba")}
                self.assertEqual({o["method"] for o in outs.values()}, {"dense", "sparse", "aba"})
                M = np.asarray(outs["aba"]["M"])
                self.close(M, M_ne, 1e-12, f"{name}: M against Newton–Euler")
                self.close(outs["aba"]["bias"], bias_ne, 1e-9, f"{name}: bias against Newton–Euler")
                qdd_py = np.linalg.solve(M_ne, tau - bias_ne)
                for m, o in outs.items():
                    self.close(o["qdd"], qdd_py, 1e-8, f"{name}: {m} against Python")
                    self.close(o["qdd"], outs["dense"]["qdd"], 1e-11, f"{name}: {m} against dense")
                    self.assertEqual(o["M"], outs["aba"]["M"])
                    self.assertEqual(o["bias"], outs["aba"]["bias"])

    def test_newton_euler_reference_matches_closed_forms(self):
        """the Python reference itself, at points with known closed forms (Examples 1 and 2)"""
        mech = MECHANISMS["pendulum_on_cart"]
        for _ in range(5):
            (x, th), (xd, thd) = self.rng.uniform(-3, 3, 2), self.rng.uniform(-2, 2, 2)
            M, b = newton_euler(mech, [x, th], [xd, thd])
            m1, m2, L, Izz, g = 2.0, 1.0, 1.0, 0.0834, 9.81
            self.close(M, [[m1 + m2, m2 * L * np.cos(th)], [m2 * L * np.cos(th), Izz + m2 * L * L]], 1e-12, "Ex. 1 M")
            self.close(b, [-m2 * L * np.sin(th) * thd ** 2, m2 * g * L * np.sin(th)], 1e-8, "Ex. 1 bias")
        mech = MECHANISMS["double_pendulum"]
        m, l1, c, J, g = 1.0, 1.0, 0.5, 0.0834, 9.81
        for _ in range(5):
            (t1, t2), (w1, w2) = self.rng.uniform(-3, 3, 2), self.rng.uniform(-2, 2, 2)
            M, b = newton_euler(mech, [t1, t2], [w1, w2])
            hc = m * l1 * c * np.sin(t2)  # Coriolis coefficient of the standard double pendulum
            expected = [-hc * (2 * w1 * w2 + w2 * w2) + m * g * (c * np.sin(t1) + l1 * np.sin(t1)) + m * g * c * np.sin(t1 + t2),
                        hc * w1 * w1 + m * g * c * np.sin(t1 + t2)]
            self.close(b, expected, 1e-8, "Ex. 2 bias")


if __name__ == "__main__":
    unittest.main(verbosity=2)
