#!/usr/bin/env bash
# The integrity table (issue 32): every scene of the repeated-texture family (rgbdtam-stress
# repeated --list), rendered once into build/integrity/, replayed with loop closure off and on,
# one row each: frames tracked and lost, false-valid and misleading poses, the frame-to-frame
# NEES (mean, median, 99th percentile) and the poses refused as ambiguous or beyond the
# search. All frames.
#   tools/integrity.sh [--frames N] [--binary path] [--set key=value]...
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/rgbdtam
stress=build/bin/rgbdtam-stress
frames=150
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift ;;
    --binary) bin=$2; shift ;;
    --set) args+=(--set "$2"); shift ;;
    *) echo "usage: tools/integrity.sh [--frames N] [--binary path] [--set key=value]..." >&2; exit 2 ;;
  esac
  shift
done
[ -x "$bin" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
cache=build/integrity
mkdir -p "$cache"
vocabulary=$PWD/data/vocabulary/tum-k10-l4.voc
printf '| %-26s | %-4s | %7s | %4s | %11s | %10s | %9s | %7s | %8s | %9s | %13s |\n' scene loop tracked lost false-valid misleading "NEES mean" median "99th pc" ambiguous "beyond search"
printf '|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n' ---------------------------- ------ --------- ------ ------------- ------------ ----------- --------- ---------- ----------- ---------------
for scene in $("$stress" repeated --list); do
  dir=$cache/$scene-$frames
  [ -d "$dir" ] || "$stress" repeated "$dir" --scene "$scene" --frames "$frames" >/dev/null || {
    rm -rf "$dir"; echo "could not render $scene" >&2; exit 1; }
  for loop in off on; do
    if [ $loop = on ]; then set_loop=(--set "loop.vocabulary=$vocabulary"); else set_loop=(--set loop.enabled=false); fi
    json=$("$bin" replay "$dir" --config "$dir/camera.conf" --json "${set_loop[@]}" "${args[@]}" 2>/dev/null)
    # A field an older binary does not print reads "-".
    field() { case "$json" in *"\"$1\":"*) printf '%s' "$json" | sed -E "s/.*\"$1\": \"?([^,\"}]*)\"?.*/\1/" ;; *) printf -- - ;; esac; }
    printf '| %-26s | %-4s | %3s/%3s | %4s | %4s of %4s | %10s | %9s | %7s | %8s | %9s | %13s |\n' \
      "$scene" "$loop" "$(field tracked)" "$(field frames)" "$(field lost)" "$(field false_valid)" \
      "$(field false_valid_checked)" "$(field misleading)" "$(field nees_mean)" "$(field nees_median)" \
      "$(field nees_p99)" "$(field ambiguous)" "$(field beyond_search)"
  done
done
