"""README's Python examples run verbatim and draw their plots; the install step works."""
import os
import re
import subprocess
import sys

import pytest

import soadyn
from conftest import ROOT

PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(soadyn.__file__)))


def python_blocks():
    text = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read()
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def test_readme_has_the_three_examples():
    blocks = python_blocks()
    assert len(blocks) == 3
    for b, most in zip(blocks, (5, 5, 10)):
        assert len(b.strip().splitlines()) <= most, b


@pytest.mark.parametrize("index,picture", [(0, "out/eig.png"), (1, "out/energy.png"), (2, None)])
def test_readme_example_runs_verbatim(tmp_path, index, picture):
    # the README's relative paths, seen from a scratch directory that receives the picture
    for d in ("scenarios", "tests"):
        os.symlink(os.path.join(ROOT, d), tmp_path / d)
    p = subprocess.run([sys.executable, "-c", python_blocks()[index]], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300, env=dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=PACKAGE_PARENT))
    assert p.returncode == 0, p.stderr
    # what a snippet writes goes under out/ (git ignores it), never beside the user's files
    written = [f.relative_to(tmp_path) for f in tmp_path.iterdir() if f.name not in ("scenarios", "tests", "out")]
    assert not written, f"README snippet {index} wrote {written} outside out/"
    if picture is None:  # the task-space step prints where the tool is and the torques
        assert p.stdout.startswith("tool at ["), p.stdout
        return
    assert (tmp_path / picture).stat().st_size > 10000


def test_cmake_install_puts_an_importable_package(tmp_path):
    """`cmake --install` (into a staging root): the package imports from there alone"""
    build = os.environ.get("SOADYN_BUILD_DIR", os.path.join(ROOT, "build"))
    p = subprocess.run(["cmake", "--install", build, "--component", "python"], capture_output=True, text=True,
                       env=dict(os.environ, DESTDIR=str(tmp_path)), timeout=120)
    assert p.returncode == 0, p.stderr
    found = [dp for dp, _, files in os.walk(tmp_path) if "__init__.py" in files]
    assert len(found) == 1 and found[0].endswith("soadyn"), found
    files = set(os.listdir(found[0]))
    assert {"__init__.py", "__init__.pyi", "_trajectory.py", "py.typed"} <= files
    assert any(f.startswith("_soadyn") and f.endswith(".so") for f in files), files
    site = os.path.dirname(found[0])
    p = subprocess.run([sys.executable, "-c", "import soadyn, sys; print(soadyn.__file__)"], capture_output=True,
                       text=True, env={"PYTHONPATH": site, "PATH": os.environ.get("PATH", "")}, timeout=60)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip().startswith(site)
