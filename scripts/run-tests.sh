#!/usr/bin/env bash
# The README's test command: sets everything up (scripts/setup.sh), then runs the whole test
# suite with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j"$(nproc)" "$@"
