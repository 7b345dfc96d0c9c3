#!/usr/bin/env bash
# The main job: install what is missing, build in Release, then for each of the note's four
# examples print its mass matrix at the initial state.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh -DSOADYN_BUILD_TESTS=OFF
for s in pendulum_on_cart double_pendulum satellite_two_arrays three_link_arm; do
  echo
  echo "== scenarios/$s.yaml"
  build/soadyn inspect "scenarios/$s.yaml"
done
