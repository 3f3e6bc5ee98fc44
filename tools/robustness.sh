#!/usr/bin/env bash
# The robustness table: every development sequence and its stress variants (faster motion by
# decimation, synthetic motion blur, dropped depth, a sensor outage, a kidnapped frame, a
# synthetic fast pan), and the degenerate synthetic scenes (a plain corridor and a plain room
# crossed at 2.4 m/s), one row each.
# Variants are generated once into build/stress/ by build/bin/rgbdtam-stress.
#   tools/robustness.sh [--set key=value]...     (TUM data: ../shared/data/tum or RGBDTAM_TUM)
# ATE is over all frames; false-valid = poses reported tracked whose motion over the preceding
# 0.5 s is off by more than 10 cm or 5 degrees (rgbdtam eval); retried = frames whose first
# estimate failed a health check, so that the wider basin (and maybe the last valid frame) ran.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin/rgbdtam
stress=build/bin/rgbdtam-stress
[ -x "$bin" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
[ -d "$tum/fr1_xyz" ] && [ -d "$tum/fr3_teddy_200" ] || { echo "no TUM data at $tum (set RGBDTAM_TUM)" >&2; exit 1; }
args=("$@")
cache=build/stress
mkdir -p "$cache"

# variant name, how to make it (run only when the folder is missing), config
make_variant() {
  local name=$1; shift
  [ -d "$cache/$name" ] && return 0
  "$@" >/dev/null || { rm -rf "$cache/$name"; echo "could not make $name" >&2; exit 1; }
}
make_variant xyz_x2 "$stress" decimate "$tum/fr1_xyz" "$cache/xyz_x2" 2
make_variant xyz_x4 "$stress" decimate "$tum/fr1_xyz" "$cache/xyz_x4" 4
make_variant xyz_x3 "$stress" decimate "$tum/fr1_xyz" "$cache/xyz_x3" 3
make_variant xyz_x3_blur33 "$stress" blur "$cache/xyz_x3" "$cache/xyz_x3_blur33" --config config/tum_fr1.conf --exposure-ms 33
make_variant xyz_depth_half "$stress" drop-depth "$tum/fr1_xyz" "$cache/xyz_depth_half" --every 2
make_variant xyz_outage_1s "$stress" cut "$tum/fr1_xyz" "$cache/xyz_outage_1s" 300 30
make_variant xyz_kidnapped "$stress" kidnap "$tum/fr1_xyz" "$cache/xyz_kidnapped" 400 100
make_variant teddy_x2 "$stress" decimate "$tum/fr3_teddy_200" "$cache/teddy_x2" 2
make_variant teddy_x3 "$stress" decimate "$tum/fr3_teddy_200" "$cache/teddy_x3" 3
make_variant teddy_blur20 "$stress" blur "$tum/fr3_teddy_200" "$cache/teddy_blur20" --config config/tum_fr3.conf --exposure-ms 20
make_variant teddy_blur40 "$stress" blur "$tum/fr3_teddy_200" "$cache/teddy_blur40" --config config/tum_fr3.conf --exposure-ms 40
make_variant teddy_depth_bursts "$stress" drop-depth "$tum/fr3_teddy_200" "$cache/teddy_depth_bursts" --burst 10/30
make_variant pan90 "$stress" pan "$cache/pan90" --peak-deg-s 90
make_variant pan180 "$stress" pan "$cache/pan180" --peak-deg-s 180
make_variant pan180_blur20 "$stress" blur "$cache/pan180" "$cache/pan180_blur20" --config "$cache/pan180/camera.conf" --exposure-ms 20
make_variant pan300 "$stress" pan "$cache/pan300" --peak-deg-s 300
make_variant pan360 "$stress" pan "$cache/pan360" --peak-deg-s 360
make_variant corridor "$stress" degenerate "$cache/corridor" --scene corridor --frames 188
make_variant plain_room "$stress" degenerate "$cache/plain_room" --scene room --frames 188

rows=(
  "fr1_xyz $tum/fr1_xyz config/tum_fr1.conf"
  "xyz_x2 $cache/xyz_x2 config/tum_fr1.conf"
  "xyz_x3 $cache/xyz_x3 config/tum_fr1.conf"
  "xyz_x4 $cache/xyz_x4 config/tum_fr1.conf"
  "xyz_x3_blur33 $cache/xyz_x3_blur33 config/tum_fr1.conf"
  "xyz_depth_half $cache/xyz_depth_half config/tum_fr1.conf"
  "xyz_outage_1s $cache/xyz_outage_1s config/tum_fr1.conf"
  "xyz_kidnapped $cache/xyz_kidnapped config/tum_fr1.conf"
  "fr3_teddy_200 $tum/fr3_teddy_200 config/tum_fr3.conf"
  "teddy_x2 $cache/teddy_x2 config/tum_fr3.conf"
  "teddy_x3 $cache/teddy_x3 config/tum_fr3.conf"
  "teddy_blur20 $cache/teddy_blur20 config/tum_fr3.conf"
  "teddy_blur40 $cache/teddy_blur40 config/tum_fr3.conf"
  "teddy_depth_bursts $cache/teddy_depth_bursts config/tum_fr3.conf"
  "pan90 $cache/pan90 $cache/pan90/camera.conf"
  "pan180 $cache/pan180 $cache/pan180/camera.conf"
  "pan180_blur20 $cache/pan180_blur20 $cache/pan180/camera.conf"
  "pan300 $cache/pan300 $cache/pan300/camera.conf"
  "pan360 $cache/pan360 $cache/pan360/camera.conf"
  "corridor $cache/corridor $cache/corridor/camera.conf"
  "plain_room $cache/plain_room $cache/plain_room/camera.conf"
)
printf '| %-18s | %6s | %7s | %8s | %11s | %10s | %9s | %5s | %7s | %6s | %9s | %8s | %6s |\n' sequence frames "ATE cm" coverage false-valid misleading "NEES mean" lost retried resets keyframes "track ms" "p95 ms"
printf '|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n' -------------------- -------- --------- ---------- ------------- ------------ ----------- ------- --------- -------- ----------- ---------- --------
for row in "${rows[@]}"; do
  read -r name dir config <<<"$row"
  json=$("$bin" replay "$dir" --config "$config" --json ${args[@]+"${args[@]}"} 2>/dev/null)
  field() { printf '%s' "$json" | sed -E "s/.*\"$1\": \"?([^,\"}]*)\"?.*/\1/"; }
  printf '| %-18s | %6s | %7.2f | %7.1f%% | %5s of %3s | %10s | %9s | %5s | %7s | %6s | %4s (+%s) | %8.2f | %6.2f |\n' \
    "$name" "$(field frames)" "$(field ate_rmse_cm)" "$(awk "BEGIN{print 100*$(field coverage)}")" \
    "$(field false_valid)" "$(field false_valid_checked)" "$(field misleading)" "$(awk "BEGIN{v=\"$(field nees_mean)\"; if (v ~ /^[0-9.eE+-]+\$/) printf \"%.2f\", v; else print \"-\"}")" \
    "$(field lost)" "$(field retried)" "$(field resets)" \
    "$(field keyframes)" "$(field reused)" "$(field track_median_ms)" "$(field track_p95_ms)"
done
