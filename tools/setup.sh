#!/usr/bin/env bash
# Set-up shared by tools/demo.sh and tools/test.sh: install the Debian packages soadyn needs
# (when missing), then configure and build in build/.  Extra arguments go to cmake's configure.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  cmake gcc g++ make pkg-config
  libeigen3-dev googletest libgtest-dev libgmock-dev libbenchmark-dev
  libsundials-dev libhdf5-dev libyaml-cpp-dev liburdfdom-dev libtinyxml2-dev libcli11-dev
  python3-numpy python3-h5py python3-matplotlib
  libjs-three chromium python3-pil   # soadyn view: three.js inlined in the page; its browser tests
  pybind11-dev python3-pybind11 python3-pytest   # the Python module and its tests
  python3-yaml python3-distributed   # soadyn sweep: sweep files, Dask
  clang libclang-rt-14-dev   # the libFuzzer targets (tools/fuzz.sh)
)
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
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j "$(nproc)"
