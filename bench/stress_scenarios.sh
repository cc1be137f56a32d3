#!/usr/bin/env bash
# The stress scenarios beyond the paper, run and summarized (3 and 4 stages):
#   stress_lightning              5.1 Mrad/s, 10-µs stroke at 10 ms: peak error, time back below
#                                 40 dB (1.146°), resets; seeds 1-5
#   stress_rotation_2mrad         2 Mrad/s deterministic rotation for 1 s: error mean/p99/max
#   stress_scrambling_60krad_1e9  1e9 samples at 60 krad/s: error max against 0.208 rad (11.9°),
#                                 peak RSS
#
#   bench/stress_scenarios.sh [--long-samples N]   (default 1e9: ~200 s per stage count on one
#                                                   core; e.g. 1e8 for a quick look)
set -euo pipefail
cd "$(dirname "$0")/.."
long_samples=1e9
while [[ $# -gt 0 ]]; do
  case $1 in
    --long-samples) long_samples=$2; shift 2 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) echo "stress_scenarios.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
dpc="${BUILD_DIR:-build}/tools/dpc/dpc"
[[ -x $dpc ]] || { echo "stress_scenarios.sh: $dpc is not built (scripts/setup.sh)" >&2; exit 1; }
long_duration_s=$(python3 -c "print(float('$long_samples') / 50e6)")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

for axes in 131 3131; do
  echo "== stages ${axes} (R$(echo "$axes" | sed 's/./&R/g; s/R$//'))"
  "$dpc" sim deploy/scenarios/stress_lightning.pbtxt --stages-axes "$axes" --seeds 1-5 --json >"$work/l.json"
  python3 - "$work/l.json" <<'PY'
import json, sys
runs = json.load(open(sys.argv[1]))["runs"]
peaks = [r["error_deg"]["max"] for r in runs]
backs = [r["recovery"]["longest_above_s"] * 1e6 for r in runs]
print("lightning (seeds 1-5): peak error %.1f-%.1f deg, back below 40 dB after %.1f-%.1f us, resets %d, "
      "error mean %.3f deg" % (min(peaks), max(peaks), min(backs), max(backs),
                               sum(r["resets"] for r in runs), sum(r["error_deg"]["mean"] for r in runs) / len(runs)))
PY
  "$dpc" sim deploy/scenarios/stress_rotation_2mrad.pbtxt --stages-axes "$axes" --json --no-progress >"$work/r.json"
  python3 - "$work/r.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
e = r["error_deg"]
print("2 Mrad/s rotation (1 s): error mean %.3f p99 %.3f max %.3f deg, resets %d"
      % (e["mean"], e["p99"], e["max"], r["resets"]))
PY
  echo "(the long run: ${long_samples} samples, progress below)"
  /usr/bin/time -v -o "$work/c.time" "$dpc" sim deploy/scenarios/stress_scrambling_60krad_1e9.pbtxt --stages-axes "$axes" \
    --duration-s "$long_duration_s" --json --progress >"$work/c.json"
  rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$work/c.time")
  python3 - "$work/c.json" "$rss_kb" <<'PY'
import json, math, sys
r = json.load(open(sys.argv[1]))
e = r["error_deg"]
print("60 krad/s, %.3g samples: error mean %.3f p99 %.3f max %.3f deg (goal < %.2f deg = 0.208 rad), "
      "resets %d, %.2f M samples/s, peak RSS %d MB"
      % (r["samples"], e["mean"], e["p99"], e["max"], math.degrees(0.208), r["resets"],
         r["samples_per_s"] / 1e6, int(sys.argv[2]) // 1024))
PY
done
