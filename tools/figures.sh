#!/usr/bin/env bash
# Regenerate every chart and table in tools/results/ (tools/results/README.md):
#   bench.{png,md,csv,json}   time per call against N, exponents, soadyn/MuJoCo ratios (tools/bench/run.sh)
#   wp_<scenario>.{png,csv}   work-precision charts (tools/work_precision.py)
#   stability.{png,md,csv}    where each method fails (tools/stability.py)
#   run_<scenario>.png        trajectories, energy error and momentum of the demo runs (tools/plot.py)
#   ensemble_{wp,stability}.{png,csv}   charts over ensembles (soadyn sweep, tools/ensemble_charts.py)
#   gradient.md               a whole run's derivatives against a plain run (tools/bench/gradient.py)
#   python_overhead.md        what a call from Python adds to the library's time (tools/bench/python_overhead.py)
#   identify_arm.png          soadyn identify: the logged arm, the scene 30 % off and the fitted scene (tools/plot.py --compare)
#   long_horizon.{md,png,csv} the satellite over 1000 s per method, variational's step against rk4's, and
#                             energy and momentum errors over 10⁶ steps (tools/long_horizon.py --chart)
#   crossover.{md,png,csv}    the double pendulum's energy error over 10³ and 10⁴ periods against CPU, the
#                             cheapest run per error, the CPU to hold the satellite's |ΔL|/L ≤ 1e-10 (tools/crossover.py)
set -euo pipefail
cd "$(dirname "$0")/.."
tools/bench/run.sh
tools/work_precision.py
tools/stability.py
mkdir -p out
for s in pendulum_on_cart double_pendulum satellite_two_arrays three_link_arm stiff_arm spherical_pendulum heavy_top \
  driven_pendulum tumbling_t_handle flexible_satellite arm_control_limits panda_gripper antenna_slew crane_slew arm_replay \
  four_bar slider_crank delta_robot; do
  build/soadyn run "scenarios/$s.yaml" -q -o "out/$s.h5"
  tools/plot.py "out/$s.h5" -o "tools/results/run_$s.png"
done
# identification: a run with known parameters, the forearm fitted back from a scene 30 % off, the
# three runs compared
build/soadyn run tests/data/identify_arm.yaml -q -o out/identify_arm.h5
build/soadyn run tests/data/identify_arm_off.yaml -q -o out/identify_arm_off.h5
build/soadyn identify tests/data/identify_arm_off.yaml --data out/identify_arm.h5 --parameters forearm -q \
  -o out/identify_arm_fitted.yaml
build/soadyn run out/identify_arm_fitted.yaml -q -o out/identify_arm_fitted.h5
tools/plot.py out/identify_arm.h5 --compare out/identify_arm_off.h5,out/identify_arm_fitted.h5 -o tools/results/identify_arm.png
# ensembles: 9000 work-precision runs (1000 initial states), 8000 stability runs; resumable in out/
build/soadyn sweep scenarios/double_pendulum_wp.sweep.yaml -o out/ensemble_wp -q
tools/ensemble_charts.py out/ensemble_wp/results.h5 -o out/ensemble_wp
cp out/ensemble_wp/ensemble_wp.{png,csv} tools/results/
build/soadyn sweep scenarios/double_pendulum_stability.sweep.yaml -o out/ensemble_stability -q
tools/ensemble_charts.py out/ensemble_stability/results.h5 -o out/ensemble_stability
cp out/ensemble_stability/ensemble_stability.{png,csv} tools/results/
{ tools/bench/gradient.py --repeat 7 --t-end 0.5; echo; tools/bench/gradient.py --repeat 5 --t-end 1.0 --every-body; } >tools/results/gradient.md
tools/bench/python_overhead.py --processes 15 >tools/results/python_overhead.md
tools/long_horizon.py --chart
tools/crossover.py
echo "figures and tables written to tools/results/"
