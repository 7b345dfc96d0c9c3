#!/usr/bin/env bash
# soadyn against Pinocchio (g++ and clang), RBDL and MuJoCo in one process and one run, with the
# same-run harness kept outside the repository (../shared/peers, its README says how it measures).
#
#   tools/bench/same_run.sh [SOADYN_BUILD_DIR]        (default: build/ of this repository)
#
# Builds soadyn's CLI target in SOADYN_BUILD_DIR (configured as a plain Release build when it is
# not configured yet), copies the harness, builds its two executables (g++: soadyn, Pinocchio,
# RBDL, MuJoCo; clang++: Pinocchio alone, run as the child "pinocchio-clang"), runs them on every
# model of the harness and saves the whole output.  Environment:
#   PEERS_HARNESS       the harness (default: <repository>/../shared/peers)
#   PEERS_PREFIX        Pinocchio and RBDL built by g++ (default /tmp/peerbuild/install)
#   PEERS_CLANG_PREFIX  Pinocchio built by clang++ (default PEERS_PREFIX-clang; left out if absent)
#   SAME_RUN_DIR        where the harness copy is built (default /tmp/same_run)
#   OUT                 the saved output (default SAME_RUN_DIR/same_run.txt)
#   ROUNDS, BUDGET      the harness's --rounds (default 3) and --budget in seconds (default 0.2)
#   STRICT=1            exit with the harness's status (non-zero when soadyn is slower than the
#                       best peer somewhere); otherwise 0 after a complete measurement
# Exits 0 with a note when the harness, the peers or MuJoCo (installed when running as root) are
# missing (the peers are optional).
set -euo pipefail
source "$(dirname "$0")/peers_env.sh"  # repo, build, harness, prefix, clang_prefix, require_harness, build_soadyn_cli
work=${SAME_RUN_DIR:-/tmp/same_run}
out=${OUT:-$work/same_run.txt}

require_harness same_run same_run
if [[ ! -d $prefix/lib/cmake/pinocchio && ! -f $prefix/include/rbdl/rbdl.h ]]; then
  echo "same_run: neither Pinocchio nor RBDL is installed at $prefix (PEERS_PREFIX; $harness/build_peers.sh builds them); nothing measured"
  exit 0
fi

# the harness needs MuJoCo (Debian libmujoco-dev): installed here when missing, as run.sh does
if ! dpkg-query -W -f='${Status}' libmujoco-dev 2>/dev/null | grep -q "install ok installed"; then
  if [[ $(id -u) -ne 0 ]]; then
    echo "same_run: the harness needs MuJoCo (sudo apt-get install -y libmujoco-dev); nothing measured"
    exit 0
  fi
  apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y libmujoco-dev
fi

build_soadyn_cli

# The harness is copied, and the copy measured: its soadyn adapter names the O(N) route
# FdMethod::ON, which soadyn's API calls FdMethod::ArticulatedBody.
echo "== harness: $harness -> $work/harness"
mkdir -p "$work"
copy_harness "$work/harness"
if ! grep -Eq '^\s*ON\b' "$repo/include/soadyn/algorithm/fd_method.hpp"; then
  sed -i 's/FdMethod::ON\b/FdMethod::ArticulatedBody/g' "$work/harness/same_run/adapter_soadyn.cc"
fi
# ... and it predates the entry points that start from the state alone, mass_matrix(model, data, q)
# and bias_forces(model, data, q, v): the copy gains them as two more routes (the harness takes
# each library's best route for 𝓜 and bias)
if grep -q 'void bias_forces(const Model& model, Data& data, const VecX& q, const VecX& v);' \
    "$repo/include/soadyn/algorithm/algorithms.hpp" && ! grep -q 'mass_matrix(q)' "$work/harness/same_run/adapter_soadyn.cc"; then
  sed -i 's|^\(\s*\)routes = {$|&\
\1    {kMass, "mass_matrix(q)", false, [this] { soadyn::mass_matrix(model, data, q); },\
\1     [this] { return permute_mat(data.Mass, vidx); }},\
\1    {kBias, "bias_forces(q,v)", false, [this] { soadyn::bias_forces(model, data, q, v); },\
\1     [this] { return permute_vec(data.bias, vidx); }},|' "$work/harness/same_run/adapter_soadyn.cc"
  grep -q 'mass_matrix(q)' "$work/harness/same_run/adapter_soadyn.cc" ||
    { echo "same_run: could not add the from-state routes to the adapter copy" >&2; exit 1; }
fi
# ... and names 𝓜 data.Mass, which Data calls M (as Python does)
if ! grep -q 'MatX Mass;' "$repo/include/soadyn/multibody/data.hpp"; then
  sed -i 's/\bdata\.Mass\b/data.M/g' "$work/harness/same_run/adapter_soadyn.cc"
fi

build_harness "$work/harness/same_run" "$work" SAME_RUN_PINOCCHIO_ONLY bench_same_run_pinocchio same_run

echo "== running (output saved to $out)"
mkdir -p "$(dirname "$out")"
status=0
cd "$work/harness"
mapfile -t models < <(ls models/chain_*.urdf models/bintree_*.urdf | sort -V)
"$work/gcc/bench_same_run" --rounds "${ROUNDS:-3}" --budget "${BUDGET:-0.2}" "${child[@]}" "${models[@]}" 2>&1 |
  tee "$out" || status=$?
echo "same_run: harness exit status $status (0: soadyn at most the best peer's time everywhere); output in $out"
if [[ ${STRICT:-0} == 1 ]]; then exit "$status"; fi
