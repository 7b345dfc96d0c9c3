#!/usr/bin/env bash
# Install what is missing, build with warnings as errors, run the whole suite through ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh -DSOADYN_WERROR=ON -DSOADYN_BUILD_TESTS=ON
echo "== running the test suite"
ctest --test-dir build --output-on-failure -j "$(nproc)"
