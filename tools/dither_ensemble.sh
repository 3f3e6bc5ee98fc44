#!/usr/bin/env bash
# How much of an accuracy number is the one draw of sensor noise a recording holds: the sequence
# tracked as recorded and as N copies whose depth moved by -1, 0 or +1 raw unit per pixel
# (rgbdtam-stress dither, seeds 1..N), far below any sensor's noise. A change is measured by the
# copies' mean and spread, not by the one recording.
#   tools/dither_ensemble.sh <sequence-dir> <config> [--seeds N] [--set key=value]...
# Prints, per run, live and final-map ATE (cm, all frames), coverage, false-valid and misleading
# poses, then the copies' mean, median, min and max. Copies go to build/stress/dither/.
# RGBDTAM_BIN=<binary> tracks with another build (an A/B comparison on the same copies).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${RGBDTAM_BIN:-build/bin/rgbdtam}
stress=build/bin/rgbdtam-stress
[ -x "$bin" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
[ $# -ge 2 ] || { echo "usage: tools/dither_ensemble.sh <sequence-dir> <config> [--seeds N] [--set key=value]..." >&2; exit 2; }
sequence=${1%/}; config=$2; shift 2
seeds=5
args=()
while [ $# -gt 0 ]; do
  case $1 in
    --seeds) seeds=$2; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
[[ $seeds =~ ^[1-9][0-9]*$ ]] || { echo "--seeds takes a positive count" >&2; exit 2; }
[ -f "$sequence/groundtruth.txt" ] || { echo "$sequence has no groundtruth.txt" >&2; exit 1; }
cache=build/stress/dither
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mkdir -p "$cache"

field() { sed -E "s/.*\"$1\": \"?([^,\"}]*)\"?.*/\1/" <<<"$2"; }
# name, folder: one row, and its live and final ATE appended to $out/ate
run() {
  local name=$1 dir=$2 json final
  json=$("$bin" replay "$dir" --config "$config" --json --quiet --final-trajectory "$out/final.txt" \
    ${args[@]+"${args[@]}"} 2>/dev/null)
  final=$(field ate_rmse_cm "$("$bin" eval "$dir/groundtruth.txt" "$out/final.txt" --json)")
  printf '| %-10s | %7.2f | %8.2f | %7.1f%% | %5s of %3s | %10s |\n' "$name" "$(field ate_rmse_cm "$json")" \
    "$final" "$(awk "BEGIN{print 100*$(field coverage "$json")}")" "$(field false_valid "$json")" \
    "$(field false_valid_checked "$json")" "$(field misleading "$json")"
  [ "$name" = recorded ] || echo "$(field ate_rmse_cm "$json") $final" >>"$out/ate"
}

printf '| %-10s | %7s | %8s | %8s | %11s | %10s |\n' run "live cm" "final cm" coverage false-valid misleading
printf '|%s|%s|%s|%s|%s|%s|\n' ------------ --------- ---------- ---------- ------------- ------------
run recorded "$sequence"
# The key names the copies' kind too: copies made before every depth image was rewritten lack
# the depth another pairing looks for, and must not be taken for these.
key=$(printf '%s every-depth-image' "$(realpath "$sequence")" | cksum | cut -d' ' -f1)
for seed in $(seq 1 "$seeds"); do
  copy=$cache/$(basename "$sequence")-$key-$seed
  if [ ! -d "$copy" ]; then
    "$stress" dither "$sequence" "$copy" --config "$config" --seed "$seed" >/dev/null ||
      { rm -rf "$copy"; echo "could not dither $sequence" >&2; exit 1; }
  fi
  run "seed $seed" "$copy"
done
# mean, median, min, max of one column of $out/ate
stats() {
  sort -n -k"$1" "$out/ate" | awk -v c="$1" '{v[NR]=$c; s+=$c} END {
    m = NR % 2 ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2
    printf "%.2f mean, %.2f median, %.2f-%.2f", s/NR, m, v[1], v[NR]}'
}
echo "dithered copies ($seeds): live ATE $(stats 1) cm; final-map ATE $(stats 2) cm"
