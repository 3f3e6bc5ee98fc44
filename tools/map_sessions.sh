#!/usr/bin/env bash
# Two sessions in one map file (all frames; false-valid as in rgbdtam eval). Per sequence:
#   1. session 1 replays the first part and saves its map (--map-out);
#   2. session 2, a new process, loads it (--map-in) and replays the rest, and separately the
#      whole sequence again; it reports no pose until it finds the camera in the map;
#   3. both sessions' trajectories are evaluated together under ONE alignment to the ground
#      truth (the replayed-again session shifted by 10 000 s, with the ground truth copied there),
#      beside one uninterrupted run: equal figures mean both sessions are in one world frame;
#   4. localise mode (map.mode = localise) over the rest: the map file's bytes must not change.
#   tools/map_sessions.sh      (TUM data: ../shared/data/tum or RGBDTAM_TUM)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/rgbdtam
stress=build/bin/rgbdtam-stress
[ -x "$bin" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
out=build/map_sessions
mkdir -p "$out"

ate() {  # groundtruth estimate frames -> "ATE cm, coverage %, false-valid"
  "$bin" eval "$1" "$2" --frames "$3" | awk '
    /^ATE/ {match($0, /RMSE [0-9.]+/); ate = substr($0, RSTART + 5, RLENGTH - 5)}
    /^coverage/ {cov = $2}
    /^false-valid/ {fv = $0; sub(/^[^:]*: */, "", fv); sub(/ poses checked.*/, "", fv)}
    END {printf "%s cm, coverage %s %%, false-valid %s", ate, cov, fv}'
}
shifted() {  # file seconds: the trajectory's stamps moved by seconds
  awk -v s="$2" '/^#/ {next} {$1 = sprintf("%.6f", $1 + s); print}' "$1"
}

# name sequence config frames split
sessions() {
  local name=$1 seq=$2 config=$3 frames=$4 split=$5 d=$out/$1
  mkdir -p "$d"
  [ -d "$d/first" ] || "$stress" cut "$seq" "$d/first" "$split" $((frames - split)) >/dev/null
  [ -d "$d/rest" ] || "$stress" cut "$seq" "$d/rest" 0 "$split" >/dev/null
  rm -f "$d/map"
  "$bin" replay "$d/first" --config "$config" --quiet --trajectory "$d/s1.txt" --map-out "$d/map" >/dev/null
  local found_rest found_again
  found_rest=$("$bin" replay "$d/rest" --config "$config" --quiet --map-in "$d/map" \
    --trajectory "$d/s2.txt" | sed -n 's/.*found in it at frame \([0-9]*\).*/\1/p')
  found_again=$("$bin" replay "$seq" --config "$config" --quiet --map-in "$d/map" \
    --trajectory "$d/again.txt" | sed -n 's/.*found in it at frame \([0-9]*\).*/\1/p')
  "$bin" replay "$seq" --config "$config" --quiet --trajectory "$d/one.txt" >/dev/null
  cat "$d/s1.txt" "$d/s2.txt" >"$d/both.txt"
  { cat "$seq/groundtruth.txt"; shifted "$seq/groundtruth.txt" 10000; } >"$d/gt_twice.txt"
  { cat "$d/s1.txt"; shifted "$d/again.txt" 10000; } >"$d/both_again.txt"
  { grep -v '^#' "$d/first/rgb.txt"; shifted "$seq/rgb.txt" 10000; } >"$d/frames_again.txt"
  local before after
  before=$(sha256sum "$d/map" | cut -c1-16)
  "$bin" replay "$d/rest" --config "$config" --quiet --map-in "$d/map" --set map.mode=localise >/dev/null
  after=$(sha256sum "$d/map" | cut -c1-16)
  echo "### $name: frames 0-$((split - 1)), then $split-$((frames - 1)) (and 0-$((frames - 1)) again)"
  "$bin" map info "$d/map" | sed -n 's/^places: \([0-9]*\).*graph edges: \([0-9]*\).*/map: \1 places, \2 edges/p'
  echo "| run | found in the map at frame | ATE under one alignment (all frames), coverage, false-valid |"
  echo "|---|---|---|"
  echo "| one uninterrupted run | - | $(ate "$seq/groundtruth.txt" "$d/one.txt" "$seq/rgb.txt") |"
  echo "| session 1 + session 2 (the rest) | ${found_rest:-never} | $(ate "$seq/groundtruth.txt" "$d/both.txt" "$seq/rgb.txt") |"
  echo "| session 1 + session 2 (all again) | ${found_again:-never} | $(ate "$d/gt_twice.txt" "$d/both_again.txt" "$d/frames_again.txt") |"
  echo "localise mode: map file $before before, $after after ($([ "$before" = "$after" ] && echo identical || echo CHANGED))"
}

sessions fr1_xyz "$tum/fr1_xyz" config/tum_fr1.conf 798 400
sessions fr3_teddy_200 "$tum/fr3_teddy_200" config/tum_fr3.conf 200 100
# The synthetic room panned at up to 30 deg/s, rendered with the Freiburg 1 camera.
[ -d "$out/pan" ] || "$stress" pan "$out/pan" --peak-deg-s 30 >/dev/null
sessions synthetic_pan "$out/pan" config/tum_fr1.conf "$(grep -vc '^#' "$out/pan/rgb.txt")" \
  $(( $(grep -vc '^#' "$out/pan/rgb.txt") / 2 ))
