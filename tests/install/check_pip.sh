#!/usr/bin/env bash
# ctest install_pip: soadyn installed as a Python package by pip, the way a user installs it.
#  - a venv made with --system-site-packages (Debian's numpy, setuptools, pybind11), then
#    `pip install --no-index --no-build-isolation SOURCE`: no network, no index;
#  - from another folder: `import soadyn` is the venv's copy, `soadyn --version` (the entry point)
#    and `python -m soadyn --version` print the CLI's line, whose version is soadyn.__version__ and
#    importlib.metadata's; `python -m soadyn run` and `soadyn inspect` work; `pip show` knows it;
#  - `pip uninstall -y soadyn` leaves no file of it in the venv;
#  - `python3 -m build --no-isolation --wheel` makes a platform wheel holding the module and the
#    executable.
# pip's build uses the test's own CMake build (SOADYN_CMAKE_BUILD_DIR, already configured: only its
# up-to-date targets are "built"), so the test compiles nothing; pyproject.toml's default,
# configuring build-pip/, is the same code with one more step.
#   check_pip.sh SOURCE_DIR BUILD_DIR SCRATCH
set -euo pipefail
source=$1 build=$2 scratch=$3
rm -rf "$scratch"
mkdir -p "$scratch/elsewhere"
fail() { echo "install_pip: $*" >&2; exit 1; }
export SOADYN_CMAKE_BUILD_DIR=$build PIP_NO_INDEX=1
unset PYTHONPATH SOADYN_EXECUTABLE

echo "== python3 -m venv --system-site-packages"
/usr/bin/python3 -m venv --system-site-packages "$scratch/venv"
py=$scratch/venv/bin/python
"$py" -c "import soadyn" 2>/dev/null && fail "soadyn importable in the venv before it was installed"

echo "== pip install --no-index --no-build-isolation $source"
(cd "$source" && "$py" -m pip install --no-index --no-build-isolation . >"$scratch/pip.log" 2>&1) ||
  { tail -40 "$scratch/pip.log"; fail "pip install failed"; }
tail -2 "$scratch/pip.log"

cd "$scratch/elsewhere"
echo "== import soadyn from another folder"
where=$("$py" -c "import soadyn; print(soadyn.__file__)")
[[ $where == "$scratch/venv/lib/python3"*"/site-packages/soadyn/__init__.py" ]] || fail "import soadyn gave $where"
version=$("$py" -c "import soadyn; print(soadyn.__version__)")
meta=$("$py" -c "import importlib.metadata as m; print(m.version('soadyn'))")
[[ $version == "$meta" ]] || fail "soadyn.__version__ $version, importlib.metadata $meta"
grep -qx "version = \"$version\"" "$source/pyproject.toml" || fail "version $version is not pyproject.toml's"

echo "== soadyn --version, python -m soadyn --version"
"$scratch/venv/bin/soadyn" --version | tee version.txt
"$py" -m soadyn --version >version_m.txt
head -1 version.txt | grep -qx "soadyn $version" || fail "soadyn --version: $(head -1 version.txt)"
cmp -s version.txt version_m.txt || fail "python -m soadyn --version differs from soadyn --version"

echo "== python -m soadyn run, soadyn inspect"
cp "$source/scenarios/double_pendulum.yaml" .
"$py" -m soadyn run double_pendulum.yaml -q -o dp.h5 --t-end 0.5 || fail "python -m soadyn run exited $?"
"$py" -c "import soadyn; t = soadyn.read_log('dp.h5'); assert t.summary.completed and len(t.t) > 10, t.summary"
"$scratch/venv/bin/soadyn" inspect double_pendulum.yaml --q 0.1,0.2 --json >inspect.json
"$py" -c "import json; d = json.load(open('inspect.json')); assert len(d['M']) == 2, d.keys()"
"$py" -m soadyn sweep --help | grep -q usage || fail "python -m soadyn sweep --help printed no usage"

echo "== pip show, pip uninstall"
"$py" -m pip show soadyn | tee show.txt
grep -qx "Version: $version" show.txt || fail "pip show: no 'Version: $version'"
"$py" -m pip uninstall -y soadyn >/dev/null
"$py" -c "import soadyn" 2>/dev/null && fail "soadyn still importable after pip uninstall"
left=$(find "$scratch/venv" -path '*soadyn*' | head -5)
[[ -z $left ]] || fail "pip uninstall left: $left"

echo "== python3 -m build --no-isolation --wheel"
(cd "$source" && /usr/bin/python3 -m build --no-isolation --wheel --outdir "$scratch/dist" . >"$scratch/build.log" 2>&1) ||
  { tail -40 "$scratch/build.log"; fail "python3 -m build failed"; }
wheel=$(ls "$scratch"/dist/soadyn-"$version"-cp3*-linux_*.whl) || fail "no platform wheel in $scratch/dist: $(ls "$scratch/dist")"
/usr/bin/python3 - "$wheel" <<'PY' || fail "the wheel lacks the module or the executable"
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
need = ["soadyn/__init__.py", "soadyn/__init__.pyi", "soadyn/_bin/soadyn"]
missing = [n for n in need if n not in names] + ([] if any(n.startswith("soadyn/_soadyn") for n in names) else ["soadyn/_soadyn*.so"])
assert not missing, missing
print(sys.argv[1].rsplit("/", 1)[-1], len(names), "files")
PY
rm -rf "$scratch"
echo "install_pip: every check passed"
