#!/usr/bin/env bash
# Regenerate every chart and table in tools/results/ (README, "Results"):
#   bench.{png,md,csv,json}   time per call against N, exponents, soadyn/MuJoCo ratios (tools/bench/run.sh)
#   wp_<scenario>.{png,csv}   work-precision charts (tools/work_precision.py)
#   stability.{png,md,csv}    where each method fails (tools/stability.py)
#   run_<scenario>.png        trajectories, energy error and momentum of the demo runs (tools/plot.py)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bench/run.sh
tools/work_precision.py
tools/stability.py
mkdir -p out
for s in pendulum_on_cart double_pendulum satellite_two_arrays three_link_arm stiff_arm; do
  build/soadyn run "scenarios/$s.yaml" -q -o "out/$s.h5"
  tools/plot.py "out/$s.h5" -o "tools/results/run_$s.png"
done
echo "figures and tables written to tools/results/"
