#!/usr/bin/env bash
# soadyn's dynamics derivatives against Pinocchio (g++ in process, clang as a child executable) in
# one run, with the derivative harness kept outside the repository (../shared/peers/derivs): q̈,
# ∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = 𝓜⁻¹, τ, ∂τ/∂q, ∂τ/∂v from the same URDF and state, each library first
# checked against the other (1e-9) and soadyn against central differences.
#
#   tools/bench/derivs_peers.sh [SOADYN_BUILD_DIR]    (default: build/ of this repository)
#
# Builds soadyn's CLI target in SOADYN_BUILD_DIR (a plain Release build when it is not configured
# yet), builds the harness's two executables, writes the robots it times besides the harness's
# chains (tools/bench/make_models.py's binary trees of 7, 15 and 63 bodies and quadruped_18, fixed
# and free; tools/humanoid_urdf.py's 50-DOF humanoid, fixed and free; tests/data/arm7.urdf) and
# saves the whole output.  Environment:
#   PEERS_HARNESS       the harness (default: <repository>/../shared/peers)
#   PEERS_PREFIX        Pinocchio built by g++ or clang (default /tmp/peerbuild/install)
#   PEERS_CLANG_PREFIX  Pinocchio built by clang++ (default PEERS_PREFIX-clang; left out if absent)
#   DERIVS_DIR          where the harness is built (default /tmp/derivs_peers)
#   OUT                 the saved output (default DERIVS_DIR/derivs_peers.txt)
#   ROUNDS              the harness's --rounds (default 3)
# Exits 0 with a note when the harness or Pinocchio is missing (the peers are optional).
set -euo pipefail
source "$(dirname "$0")/peers_env.sh"  # repo, build, harness, prefix, clang_prefix, require_harness, build_soadyn_cli
work=${DERIVS_DIR:-/tmp/derivs_peers}
out=${OUT:-$work/derivs_peers.txt}

require_harness derivs_peers derivs
if [[ ! -d $prefix/lib/cmake/pinocchio ]]; then
  echo "derivs_peers: no Pinocchio at $prefix (PEERS_PREFIX; $harness/build_peers.sh builds it); nothing measured"
  exit 0
fi

build_soadyn_cli

echo "== harness: $harness/derivs"
mkdir -p "$work"
copy_harness "$work/harness"
build_harness "$work/harness/derivs" "$work" DERIVS_PINOCCHIO_ONLY bench_derivs_pinocchio derivs_peers

# the binary trees, and the robots: the quadruped and the humanoid as URDF, fixed and free-floating (":free")
models=$work/models
mkdir -p "$models"
/usr/bin/python3 "$repo/tools/bench/make_models.py" "$models" >/dev/null
/usr/bin/python3 "$repo/tools/humanoid_urdf.py" -o "$models/humanoid.urdf" >/dev/null

echo "== running (output saved to $out)"
mkdir -p "$(dirname "$out")"
cd "$harness"
"$work/gcc/bench_derivs" --rounds "${ROUNDS:-3}" "${child[@]}" \
  models/chain_8.urdf models/chain_32.urdf models/chain_64.urdf \
  "$models/tree_7.urdf" "$models/tree_15.urdf" "$models/tree_63.urdf" "$repo/tests/data/arm7.urdf" \
  "$models/quadruped_18.urdf" "$models/quadruped_18.urdf:free" "$models/humanoid.urdf" "$models/humanoid.urdf:free" 2>&1 |
  tee "$out"
