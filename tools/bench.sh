#!/usr/bin/env bash
# Replays one TUM sequence with the release binary, evaluates it, and prints one table row.
#   tools/bench.sh <sequence-dir> [config] [--header] [--set key=value]...
# ATE is over all frames (TUM evaluate_ate.py conventions), beside coverage and the false-valid
# poses (rgbdtam eval); times are this machine's.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/rgbdtam
[ -x "$bin" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
seq=${1:?usage: tools/bench.sh <sequence-dir> [config] [--header] [--set key=value]...}
shift
config=config/tum_fr1.conf
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then config=$1; shift; fi
header=false
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --header) header=true ;;
    --set) args+=(--set "$2"); shift ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done
if $header; then
  printf '| %-12s | %-8s | %6s | %8s | %11s | %11s | %5s | %8s | %8s | %9s | %8s | %9s |\n' sequence residuals frames coverage "ATE cm" false-valid lost "RPE cm/s" "RPE °/s" "track ms" "p95 ms" keyframes
  printf '|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n' -------------- ---------- -------- ---------- ------------- ------------- ------- ---------- ---------- ----------- ---------- -----------
fi
json=$("$bin" replay "$seq" --config "$config" --json "${args[@]}" 2>/dev/null)
field() { printf '%s' "$json" | sed -E "s/.*\"$1\": \"?([^,\"}]*)\"?.*/\1/"; }
printf '| %-12s | %-8s | %6s | %7.1f%% | %11.2f | %4s of %4s | %5s | %8.2f | %8.2f | %9.2f | %8.2f | %4s (+%s) |\n' \
  "$(basename "$seq")" "$(field residuals)" "$(field frames)" "$(awk "BEGIN{print 100*$(field coverage)}")" \
  "$(field ate_rmse_cm)" "$(field false_valid)" "$(field false_valid_checked)" "$(field lost)" \
  "$(field rpe_trans_cm_s)" "$(field rpe_rot_deg_s)" \
  "$(field track_median_ms)" "$(field track_p95_ms)" "$(field keyframes)" "$(field reused)"
