#!/usr/bin/env bash
# The main job: install what is missing, build in Release, then for each of the note's four
# examples and the two ball-joint scenes print its mass matrix at the initial state; simulate those
# and the scenes where methods break (stiff arm, driven pendulum, tumbling T-handle, flexible
# satellite), the prescribed-motion scenes (antenna slew, crane, arm replay) and the closed-loop
# scenes (four-bar, slider-crank, Delta robot) with CVODE (writing out/<scenario>.h5), print a table of the runs and plot them
# (out/<scenario>.png).  Builds the soadyn executable only (tools/test.sh builds the rest).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh --demo
scenarios=(pendulum_on_cart double_pendulum satellite_two_arrays three_link_arm spherical_pendulum heavy_top)
runs=("${scenarios[@]}" stiff_arm driven_pendulum tumbling_t_handle flexible_satellite antenna_slew crane_slew arm_replay
  four_bar slider_crank delta_robot)

for s in "${scenarios[@]}"; do
  echo
  echo "== scenarios/$s.yaml: system mass matrix at the initial state"
  build/soadyn inspect "scenarios/$s.yaml" | sed -n '/^mass matrix/,/^bias/p' | sed '$d'
done

echo
echo "== simulations (CVODE, the scenario's own settings)"
printf "%-22s %-12s %8s %10s %10s %13s  %s\n" scenario method t_end steps "CPU [s]" "E balance" output
mkdir -p out
for s in "${runs[@]}"; do
  summary=$(build/soadyn run "scenarios/$s.yaml" -o "out/$s.h5")
  field() { grep "^$1" <<<"$summary" | sed "s/^$1 *//"; }
  printf "%-22s %-12s %8s %10s %10s %13s  %s\n" "$s" "$(field method | cut -d' ' -f1)" \
    "$(field 't reached' | cut -d' ' -f1)" "$(field steps)" "$(field 'CPU time' | cut -d' ' -f1)" \
    "$(field 'energy balance error' | cut -d' ' -f1)" "out/$s.h5"
done

echo
echo "== plots"
for s in "${runs[@]}"; do tools/plot.py "out/$s.h5" -o "out/$s.png"; done

echo
echo "== 3D pages (open in a browser)"
for s in "${runs[@]}"; do build/soadyn view "out/$s.h5" -q -o "out/$s.html" && echo "out/$s.html"; done
