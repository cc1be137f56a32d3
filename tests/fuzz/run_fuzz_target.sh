#!/usr/bin/env bash
# Runs one fuzz target on a copy of its seed corpus (ctest fuzz_<target>; scripts/fuzz.sh):
#
#   run_fuzz_target.sh <target binary> <seed dir> <artifact dir> [libFuzzer options…]
#
# The corpus grows in a temporary directory (removed afterwards), so the seeds stay as they are
# and runs do not pile up. A crash is written to <artifact dir>/crash-<sha1> (libFuzzer's
# artifact), and the exit status is libFuzzer's: 0 when the run ended with no crash.
set -euo pipefail
if (($# < 3)); then
  echo "usage: $0 <target binary> <seed dir> <artifact dir> [libFuzzer options...]" >&2
  exit 2
fi
binary=$1 seeds=$2 artifacts=$3
shift 3
corpus=$(mktemp -d "${TMPDIR:-/tmp}/dpc-fuzz.XXXXXX")
trap 'rm -rf "$corpus"' EXIT
cp -R "$seeds"/. "$corpus"/
mkdir -p "$artifacts"
"$binary" -print_final_stats=1 -artifact_prefix="$artifacts/" "$@" "$corpus"
