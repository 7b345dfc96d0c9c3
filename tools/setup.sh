#!/usr/bin/env bash
# Set-up shared by tools/demo.sh and tools/test.sh: install the Debian packages soadyn needs
# (when missing), then configure and build in build/.
#   tools/setup.sh [--demo] [cmake configure arguments…]
# --demo: only what the demo needs (the packages to build and run soadyn and tools/plot.py; the
# soadyn executable alone is built).  Otherwise everything: tests, benchmarks, Python module.
# Both compile with the same flags (warnings are errors in both), so tools/test.sh after
# tools/demo.sh reuses the library's and the executable's objects and builds only the rest.
set -euo pipefail
cd "$(dirname "$0")/.."

demo=0
if [[ ${1:-} == --demo ]]; then
  demo=1
  shift
fi
packages=(
  cmake gcc g++ make pkg-config
  libeigen3-dev libsundials-dev libhdf5-dev libyaml-cpp-dev liburdfdom-dev libtinyxml2-dev libcli11-dev
  libmujoco-dev                                     # MJCF import (MuJoCo's compiler); optional to CMake
  libjs-three                                       # soadyn view: three.js inlined in the page
  python3-numpy python3-h5py python3-matplotlib     # tools/plot.py
)
if ((!demo)); then
  packages+=(
    googletest libgtest-dev libgmock-dev libbenchmark-dev
    chromium python3-pil                            # soadyn view's browser tests
    pybind11-dev python3-pybind11 python3-pytest    # the Python module and its tests
    python3-venv python3-pip python3-setuptools python3-wheel python3-build  # pip install . and the wheel (ctest install_pip)
    python3-yaml python3-distributed                # soadyn sweep: sweep files, Dask
    clang libclang-rt-14-dev                        # the libFuzzer targets (tools/fuzz.sh)
    ccache                                          # tools/mutation_check.py's scratch build reuses these objects
  )
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [[ $(id -u) -ne 0 ]]; then
    echo "soadyn needs these Debian packages: ${missing[*]}" >&2
    echo "install them with:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  echo "== installing ${missing[*]}"
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y "${missing[@]}"
fi

echo "== configuring and building (Release) in build/"
# through ccache when it is there, with paths relative to this tree (CCACHE_BASEDIR), so that a copy
# of the tree elsewhere (tools/mutation_check.py's scratch build) compiles only the files it changed
launcher=()
if command -v ccache >/dev/null; then
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=env;CCACHE_BASEDIR=$PWD;ccache")
fi
if ((demo)); then
  # an existing build/ keeps its options (a later tools/test.sh sets them all again); the options
  # left off here (tests, benchmarks, Python) add targets but change no flag of soadyn's
  if [[ -f build/CMakeCache.txt ]]; then
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSOADYN_WERROR=ON "${launcher[@]}" "$@"
  else
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSOADYN_WERROR=ON \
      -DSOADYN_BUILD_TESTS=OFF -DSOADYN_BUILD_BENCH=OFF -DSOADYN_PYTHON=OFF "${launcher[@]}" "$@"
  fi
  cmake --build build -j "$(nproc)" --target soadyn_cli
else
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSOADYN_WERROR=ON \
    -DSOADYN_BUILD_TESTS=ON -DSOADYN_BUILD_BENCH=ON -DSOADYN_PYTHON=ON "${launcher[@]}" "$@"
  cmake --build build -j "$(nproc)"
fi
