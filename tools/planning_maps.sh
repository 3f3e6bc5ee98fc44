#!/usr/bin/env bash
# Maps to plan with from a replay's map file, on the TUM sequences: the 2-D occupancy grid
# (map_server's PGM + YAML, and a PNG preview) and the 3-D OctoMap .bt, opened by OctoMap's own
# convert_octree; with the map file's size and its save and load times.
# Gravity: the TUM ground truth's z is up, so the up direction in the map's world frame (the
# first frame's camera) is the third row of the first ground-truth rotation; it stands in for an
# autopilot's attitude, which the map does not record yet.
#   tools/planning_maps.sh [heights]     (default -1.2,0.5: desk tops are obstacles)
#   TUM data: ../shared/data/tum or RGBDTAM_TUM
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/rgbdtam
octomap=build/bin/rgbdtam-octomap
[ -x "$bin" ] && [ -x "$octomap" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
heights=${1:--1.2,0.5}
out=build/planning_maps
mkdir -p "$out"

# The up direction in the first tracked frame's camera frame, from the ground truth's pose
# nearest to the first colour frame.
up_of() {
  local first
  first=$(grep -v '^#' "$1/rgb.txt" | head -1 | cut -d' ' -f1)
  grep -v '^#' "$1/groundtruth.txt" | awk -v t="$first" '
    { d = $1 - t; if (d < 0) d = -d; if (best == "" || d < best) { best = d; x = $5; y = $6; z = $7; w = $8 } }
    END { printf "%.6f,%.6f,%.6f", 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y) }'
}

for entry in fr1_xyz:config/tum_fr1.conf fr3_teddy_200:config/tum_fr3.conf; do
  name=${entry%%:*} config=${entry#*:} seq=$tum/${entry%%:*}
  d=$out/$name
  mkdir -p "$d"
  echo "### $name"
  "$bin" replay "$seq" --config "$config" --quiet --map-out "$d/map" --trajectory "$d/t.txt" |
    grep -E "^map file|^ATE" || true
  "$bin" replay "$seq" --config "$config" --quiet --map-in "$d/map" --max-frames 1 |
    grep -E "^map file" || true
  "$bin" map info "$d/map" | grep -E "^map file|^places"
  up=$(up_of "$seq")
  "$bin" map export "$d/map" --grid "$d/grid" --png --heights "$heights" --up "$up"
  "$octomap" "$d/map" "$d/map.bt" --up "$up"
  echo "OctoMap's convert_octree reads it:"
  convert_octree "$d/map.bt" "$d/map.ot" 2>&1 | grep -iE "node|read|error" | head -3
done
