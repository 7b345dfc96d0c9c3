"""The Python examples of README.md and src/python/README.md run verbatim and draw their plots; the
install step works."""
import os
import re
import subprocess
import sys

import pytest

import soadyn
from conftest import ROOT

PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(soadyn.__file__)))


def python_blocks(readme):
    """the ```python blocks of a README's "## Python" section (or of the whole file without one)"""
    text = open(os.path.join(ROOT, readme), encoding="utf-8").read()
    if "\n## Python\n" in text:
        text = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_examples_are_short():
    top, package = python_blocks("README.md"), python_blocks("src/python/README.md")
    assert len(top) == 1 and len(top[0].strip().splitlines()) <= 10, top
    assert len(package) == 2 and all(len(b.strip().splitlines()) <= 5 for b in package), package


@pytest.mark.parametrize("readme,index,picture", [("README.md", 0, None), ("src/python/README.md", 0, "out/eig.png"),
                                                  ("src/python/README.md", 1, "out/energy.png")])
def test_readme_example_runs_verbatim(tmp_path, readme, index, picture):
    # the README's relative paths, seen from a scratch directory that receives the picture
    for d in ("scenarios", "tests"):
        os.symlink(os.path.join(ROOT, d), tmp_path / d)
    p = subprocess.run([sys.executable, "-c", python_blocks(readme)[index]], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300, env=dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=PACKAGE_PARENT))
    assert p.returncode == 0, p.stderr
    # what a snippet writes goes under out/ (git ignores it), never beside the user's files
    written = [f.relative_to(tmp_path) for f in tmp_path.iterdir() if f.name not in ("scenarios", "tests", "out")]
    assert not written, f"README snippet {index} wrote {written} outside out/"
    if picture is None:  # the task-space step prints where the tool is and the torques
        assert p.stdout.startswith("tool at ["), p.stdout
        return
    assert (tmp_path / picture).stat().st_size > 10000


def test_identification_example_runs_verbatim(tmp_path):
    """src/python/README.md's Identification snippet: the forearm's mass fitted back from 1.3 kg to 1,
    rank 10, nothing unidentifiable, the fitted scene written under out/ and loadable"""
    text = open(os.path.join(ROOT, "src/python/README.md"), encoding="utf-8").read()
    (block,) = re.findall(r"```python\n(.*?)```", text.split("\n## Identification\n", 1)[1].split("\n## ", 1)[0], re.S)
    for d in ("scenarios", "tests"):
        os.symlink(os.path.join(ROOT, d), tmp_path / d)
    p = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env=dict(os.environ, PYTHONPATH=PACKAGE_PARENT))
    assert p.returncode == 0, p.stderr
    mass, error, rank, rest = p.stdout.split(" ", 3)
    assert abs(float(mass) - 1.0) < 1e-9 and float(error) < 1e-9 and rank == "10" and rest.strip() == "[]", p.stdout
    fitted = soadyn.load_scenario(str(tmp_path / "out" / "identify_fit.yaml"))
    assert abs(fitted.model.masses[fitted.model.body_index("forearm")] - 1.0) < 1e-9


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
