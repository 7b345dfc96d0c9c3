# Sourced by tools/bench/same_run.sh and tools/bench/derivs_peers.sh, which time soadyn against
# peer libraries with harnesses kept outside the repository: where the repository, the soadyn
# build (the caller's first argument, default build/), the harnesses (PEERS_HARNESS) and the peer
# installs (PEERS_PREFIX, PEERS_CLANG_PREFIX) are, and build_soadyn_cli, which configures the build
# as a plain Release build when it is not configured yet and builds soadyn's CLI target.
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(realpath -m "${1:-$repo/build}")
harness=${PEERS_HARNESS:-$repo/../shared/peers}
prefix=${PEERS_PREFIX:-/tmp/peerbuild/install}
clang_prefix=${PEERS_CLANG_PREFIX:-$prefix-clang}

build_soadyn_cli() {
  echo "== soadyn: $build"
  if [[ ! -f $build/CMakeCache.txt ]]; then
    cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release
  fi
  cmake --build "$build" -j2 --target soadyn_cli
}
