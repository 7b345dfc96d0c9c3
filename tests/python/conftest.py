"""Shared by the Python module's tests: paths, the command line as the reference, random trees."""
import json
import os
import subprocess

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENARIOS = os.path.join(ROOT, "scenarios")
SOADYN = os.environ.get("SOADYN", os.path.join(ROOT, "build", "soadyn"))


def cli(*args):
    return subprocess.run([SOADYN, *map(str, args)], capture_output=True, text=True, timeout=120)


def inspect_json(path, q=None, qd=None, tau=None, method="aba", free_root=False):
    """`soadyn inspect --json` at a state: 17 significant digits, so the numbers round-trip"""
    args = ["inspect", path, "--json", "--method", method]
    for name, x in (("--q", q), ("--qd", qd), ("--tau", tau)):
        if x is not None:
            args += [name, ",".join(repr(float(v)) for v in x)]
    if free_root:
        args.append("--free-root")
    p = cli(*args)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def cli_error(*args):
    """the command line's one-line message for bad input, without its 'soadyn: error: ' prefix"""
    p = cli(*args)
    assert p.returncode == 2, p.stdout + p.stderr
    line = p.stderr.strip()
    assert line.startswith("soadyn: error: "), line
    return line[len("soadyn: error: "):]


def assert_close(got, expected, tol):
    got, expected = np.asarray(got, float), np.asarray(expected, float)
    assert got.shape == expected.shape, (got.shape, expected.shape)
    scale = max(1.0, float(np.abs(expected).max())) if expected.size else 1.0
    err = float(np.abs(got - expected).max()) if got.size else 0.0
    assert err <= tol * scale, f"max error {err:.3e} > {tol:g} * {scale:g}\n{got}\nvs\n{expected}"


def random_tree_yaml(rng, n, free_root=False, prismatic=0.2, ball=0.15, planar=0.1, fixed=1):
    """A scenario with n moving bodies on random parents (plus `fixed` welded ones), joints of every
    kind (revolute, prismatic, ball, planar; a free root if asked), random axes,
    placements (xyz, rpy), masses, centres of mass and full inertia tensors, and random gravity."""
    def vec(lo=-1.0, hi=1.0, k=3):
        return "[" + ", ".join(repr(float(x)) for x in rng.uniform(lo, hi, k)) + "]"

    def inertia():
        sq = rng.uniform(0.05, 1.0, 3)  # Σ m x², Σ m y², Σ m z²: a physical tensor
        principal = np.array([sq[1] + sq[2], sq[0] + sq[2], sq[0] + sq[1]])
        a = rng.normal(size=4)
        a /= np.linalg.norm(a)
        w, x, y, z = a
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        I = R @ np.diag(principal) @ R.T
        I = 0.5 * (I + I.T)
        return "[" + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in I) + "]"

    total = n + fixed
    welded = set(rng.choice(np.arange(1, total), size=min(fixed, total - 1), replace=False).tolist()) if total > 1 else set()
    lines = ["name: random_tree", f"gravity: {vec(-10, 10)}", "bodies:"]
    for i in range(total):
        parent = "world" if i == 0 else f"b{int(rng.integers(0, i))}"
        if i == 0 and free_root:
            joint = "{type: free, name: j0}"
        elif i in welded:
            joint = f"{{type: fixed, name: j{i}}}"
        else:
            u = rng.uniform()
            kind = "prismatic" if u < prismatic else "ball" if u < prismatic + ball else \
                "planar" if u < prismatic + ball + planar else "revolute"
            joint = f"{{type: ball, name: j{i}}}" if kind == "ball" else f"{{type: {kind}, name: j{i}, axis: {vec()}}}"
        lines += [f"  - name: b{i}", f"    parent: {parent}", f"    joint: {joint}"]
        if not (i == 0 and free_root):
            lines.append(f"    origin: {{xyz: {vec(-0.6, 0.6)}, rpy: {vec(-3, 3)}}}")
        lines += [f"    mass: {rng.uniform(0.2, 3.0)!r}", f"    com: {vec(-0.4, 0.4)}", f"    inertia: {inertia()}"]
    return "\n".join(lines) + "\n"


@pytest.fixture
def rng():
    return np.random.default_rng(20261201)
