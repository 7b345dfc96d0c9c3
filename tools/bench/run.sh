#!/usr/bin/env bash
# Run every benchmark, with MuJoCo as a peer (installed here if missing), and write
# tools/results/bench.{json,csv,md,png}: time per call against N, fitted growth exponents over
# N = 16..256, soadyn / fastest peer per N.  Quote ratios from one run: the machines are shared.
#   PEERS_PREFIX=/tmp/peerbuild/install tools/bench/run.sh   adds Pinocchio and RBDL as peers
#   (../shared/peers/build_peers.sh builds them there; with CLANG=1 also Pinocchio compiled by clang
#   in PREFIX-clang).  Without PEERS_PREFIX they are left out with a note.
# BENCH_MIN_TIME (default 0.1 s) is Google Benchmark's minimum time per benchmark; BENCH_FILTER, when
# set, its --benchmark_filter (a leading '-' leaves the matches out).  Each benchmark runs
# BENCH_REPETITIONS times (default 3), interleaved at random with all the others, and the report
# keeps the fastest repetition: a burst of load on the shared machine then spoils one repetition,
# not a ratio.
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! dpkg-query -W -f='${Status}' libmujoco-dev 2>/dev/null | grep -q "install ok installed"; then
  if [[ $(id -u) -eq 0 ]]; then
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y libmujoco-dev
  else
    echo "MuJoCo is not installed; the peer is skipped (sudo apt-get install -y libmujoco-dev to add it)" >&2
  fi
fi
tools/setup.sh -DSOADYN_BUILD_BENCH=ON "-DSOADYN_PEERS_PREFIX=${PEERS_PREFIX:-}"
out=tools/results
mkdir -p "$out" build/bench_models
tools/bench/make_models.py build/bench_models
# the frame-Jacobian rows' robots (bench_peers.cpp kFrameRobots)
cp tests/data/arm7.urdf build/bench_models/
tools/humanoid_urdf.py -o build/bench_models/humanoid.urdf
SOADYN_BENCH_MODELS=build/bench_models build/soadyn_bench --benchmark_min_time="${BENCH_MIN_TIME:-0.1}" ${BENCH_FILTER:+"--benchmark_filter=$BENCH_FILTER"} \
  --benchmark_repetitions="${BENCH_REPETITIONS:-3}" --benchmark_enable_random_interleaving=true \
  --benchmark_report_aggregates_only=false --benchmark_display_aggregates_only=true \
  --benchmark_format=console --benchmark_out_format=json --benchmark_out=build/bench_all.json
# every repetition stays in build/bench_all.json; tools/results/bench.json keeps the figures used
tools/bench/report.py build/bench_all.json -o "$out" --keep "$out/bench.json"
