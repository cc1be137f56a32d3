#!/usr/bin/env bash
# Memory does not grow with run length: runs the paper scenario for 1e9 samples (20 s of
# simulated time at 50 MHz) and prints the peak resident set size. Goal: < 50 MB.
#
#   bench/sim_memory.sh [SAMPLES]     (default 1e9; a trace is not written)
set -euo pipefail
cd "$(dirname "$0")/.."
samples="${1:-1e9}"
duration_s=$(python3 -c "print(float('$samples') / 50e6)")
dpc="${BUILD_DIR:-build}/tools/dpc/dpc"
report=$(mktemp)
trap 'rm -f "$report"' EXIT
/usr/bin/time -v "$dpc" sim deploy/scenarios/paper_fig4.pbtxt --duration-s "$duration_s" \
  --json --no-progress 2>"$report" | python3 -c '
import json, sys
r = json.load(sys.stdin)
print("samples %.3g  speed %.2f M samples/s  error mean %.3f deg"
      % (r["samples"], r["samples_per_s"] / 1e6, r["error_deg"]["mean"]))'
rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$report")
echo "peak RSS $((rss_kb / 1024)) MB (goal < 50 MB)"
