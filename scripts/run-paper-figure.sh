#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), then runs the paper's
# 3-stage scenario (Fig. 3) in the closed-loop simulator and draws its figure.
#
#   scripts/run-paper-figure.sh                       # Fig. 3 → out/paper_fig3.png
#   scripts/run-paper-figure.sh paper_fig4            # another shipped scenario
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scenario="${1:-paper_fig3}"
mkdir -p out
"${BUILD_DIR:-build}"/tools/dpc/dpc sim "deploy/scenarios/${scenario}.pbtxt" \
  --trace "out/${scenario}.csv" --plot "out/${scenario}.png"
