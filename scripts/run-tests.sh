#!/usr/bin/env bash
# The README's test command: sets everything up (scripts/setup.sh), then runs the whole test
# suite with CTest, then fuzzes the checks at the services' edges for a bounded time
# (scripts/fuzz.sh: a clang build of its own, each target DPC_FUZZ_SECONDS, default 30 s).
# Arguments go to CTest (e.g. -R Bench); with arguments, no fuzzing.
set -euo pipefail
cd "$(dirname "$0")/.."
DPC_SETUP_TESTS=1 scripts/setup.sh
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" "$@"
if [[ $# -eq 0 ]]; then
  scripts/fuzz.sh --seconds "${DPC_FUZZ_SECONDS:-30}" --jobs "$(nproc)"
fi
