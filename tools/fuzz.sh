#!/usr/bin/env bash
# Build the libFuzzer targets with Debian clang (address + undefined sanitizers) in build-fuzz/,
# or run one of them for a bounded time on a seed corpus made from scenarios/ (scenario),
# tests/fuzz/seeds/ and tests/data/urdf/ (urdf), or the real run files in tests/fuzz/seeds/*.h5
# (run_file: the run-file reader, inputs up to 256 KiB).
#   tools/fuzz.sh build
#   tools/fuzz.sh run scenario|urdf|run_file SECONDS
# Exits 77 (skipped) only when clang with libFuzzer is not installed; a finding exits 1.
set -euo pipefail
cd "$(dirname "$0")/.."
CLANG=$(command -v clang++ || command -v clang++-14 || true)
if [[ -z "$CLANG" ]]; then echo "fuzz: clang++ not installed, skipped"; exit 77; fi
if ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  echo "fuzz: libFuzzer runtime (libclang-rt-*-dev) not installed, skipped"; exit 77
fi

case "${1:-}" in
  build)
    # -O1 and line tables only: what the sanitizers' reports need (file:line in every frame), at a
    # fraction of the compile time of RelWithDebInfo's -O2 -g; the library holds only the sources
    # the fuzz targets reach (CMakeLists.txt, SOADYN_FUZZ), the unreached ones it links at -O0, and
    # the rest in unity batches of four (each batch parses Eigen once: -20 % of the CPU time)
    CXX="$CLANG" cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOADYN_FUZZ=ON \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
      -DSOADYN_BUILD_TESTS=OFF -DSOADYN_BUILD_BENCH=OFF -DSOADYN_PYTHON=OFF -DSOADYN_NATIVE=OFF \
      -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=4 >/dev/null
    cmake --build build-fuzz -j "$(nproc)" --target fuzz_scenario fuzz_urdf fuzz_run_file
    ;;
  run)
    target=$2 seconds=$3
    corpus=build-fuzz/corpus_$target
    rm -rf "$corpus" && mkdir -p "$corpus"
    max_len=8192
    case $target in
      scenario) cp scenarios/*.yaml "$corpus/" ;;
      run_file) cp tests/fuzz/seeds/*.h5 "$corpus/"; max_len=262144
        export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan_hdf5.supp ;;  # libhdf5's own leaks
      *) cp tests/fuzz/seeds/*.urdf tests/data/urdf/*.urdf "$corpus/" ;;
    esac
    mkdir -p build-fuzz/findings_$target
    log=build-fuzz/fuzz_$target.log
    status=0
    ASAN_OPTIONS=detect_leaks=1 ./build-fuzz/fuzz_$target "$corpus" -max_total_time="$seconds" -timeout=10 \
      -rss_limit_mb=2048 -max_len="$max_len" -print_final_stats=1 -artifact_prefix=build-fuzz/findings_$target/ \
      >"$log" 2>&1 || status=$?
    grep -E "^(INFO: seed corpus|stat::number_of_executed_units|stat::peak_rss)" "$log" || true
    if ((status != 0)); then
      echo "fuzz_$target found a problem (exit $status):"
      grep -A40 -E "==[0-9]+==ERROR|deadly signal|Test unit written" "$log" | head -80
    fi
    # libFuzzer exits 77 on a finding, which ctest would read as "skipped": any failure is 1 here
    ((status == 0)) || exit 1
    ;;
  *) echo "usage: tools/fuzz.sh build | run scenario|urdf|run_file SECONDS" >&2; exit 2 ;;
esac
