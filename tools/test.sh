#!/usr/bin/env bash
# Install what is missing, build with warnings as errors (tools/setup.sh: the flags tools/demo.sh
# builds with, so after it only the tests, benchmarks and Python module compile), run the whole
# suite through ctest, then the mutation check of the fast paths.
# setup.sh has installed every tool a test needs (clang and libFuzzer, chromium), so a test that
# reports "skipped" here hides a failure: the run fails.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
echo "== running the test suite"
status=0
ctest --test-dir build --output-on-failure -j "$(nproc)" 2>&1 | tee build/ctest.log || status=$?
if grep -q "The following tests did not run" build/ctest.log; then
  echo "== tests were skipped although tools/setup.sh installed what they need: failing" >&2
  exit 1
fi
# the fast paths' mutants, and no mutation of the table gone stale (a scratch copy, its objects from
# ccache: only the mutated files compile)
echo "== mutation check (tools/mutation_check.py --ci)"
/usr/bin/python3 tools/mutation_check.py --ci || status=1
exit "$status"
