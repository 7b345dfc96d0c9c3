# Sourced by tools/bench/same_run.sh and tools/bench/derivs_peers.sh, which time soadyn against
# peer libraries with harnesses kept outside the repository: where the repository, the soadyn
# build (the caller's first argument, default build/), the harnesses (PEERS_HARNESS) and the peer
# installs (PEERS_PREFIX, PEERS_CLANG_PREFIX) are; require_harness, which ends the caller with a
# note when its harness is missing (the peers are optional); build_soadyn_cli, which configures the build
# as a plain Release build when it is not configured yet and builds soadyn's CLI target; and
# build_harness, which builds a harness twice: by g++ against soadyn and the g++ Pinocchio, and by
# clang++ with Pinocchio alone when a clang-built Pinocchio is installed.
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(realpath -m "${1:-$repo/build}")
harness=${PEERS_HARNESS:-$repo/../shared/peers}
prefix=${PEERS_PREFIX:-/tmp/peerbuild/install}
clang_prefix=${PEERS_CLANG_PREFIX:-$prefix-clang}

# require_harness NAME DIR: exit 0 with a note unless the harnesses hold DIR/CMakeLists.txt
require_harness() {
  if [[ ! -f $harness/$2/CMakeLists.txt ]]; then
    echo "$1: no harness at $harness (set PEERS_HARNESS to the directory holding $2/); nothing measured"
    exit 0
  fi
}

# copy_harness DEST: the harness copied to DEST (file times kept, so a rebuild is incremental), its
# soadyn adapters including soadyn/soadyn.hpp: they predate the layered headers (soadyn/<layer>/…)
copy_harness() {
  rm -rf "$1"
  cp -a "$harness" "$1"
  grep -rlE '#include "soadyn/[a-z_]+\.hpp"' "$1" | xargs -r sed -i -E 's|#include "soadyn/[a-z_]+\.hpp"|#include "soadyn/soadyn.hpp"|'
}

build_soadyn_cli() {
  echo "== soadyn: $build"
  if [[ ! -f $build/CMakeCache.txt ]]; then
    cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release
  fi
  cmake --build "$build" -j2 --target soadyn_cli
}

# build_harness SOURCE WORK ONLY_OPTION EXECUTABLE NAME: SOURCE built by g++ in WORK/gcc, and by
# clang++ in WORK/clang with -DONLY_OPTION=ON (Pinocchio alone); sets child to the harness's
# arguments that run WORK/clang/EXECUTABLE as the pinocchio-clang column (empty without it)
build_harness() {
  local source=$1 work=$2 only=$3 exe=$4 name=$5
  cmake -S "$source" -B "$work/gcc" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=g++ \
    -DSOADYN_BUILD_DIR="$build" -DSOADYN_SOURCE_DIR="$repo" -DPEERS_PREFIX="$prefix"
  cmake --build "$work/gcc" -j2
  child=()
  if [[ -d $clang_prefix/lib/cmake/pinocchio ]] && command -v clang++ >/dev/null; then
    cmake -S "$source" -B "$work/clang" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
      -D"$only"=ON -DPEERS_PREFIX="$clang_prefix"
    cmake --build "$work/clang" -j2
    child=(--child-exe "$work/clang/$exe" --child-name pinocchio-clang)
  else
    echo "$name: no Pinocchio built by clang++ at $clang_prefix: the pinocchio-clang column is left out"
  fi
}
