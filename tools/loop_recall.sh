#!/usr/bin/env bash
# Revisits found, from the ground truth (issue 19's measure), on every development sequence and
# variant, one row each:
#   - a keyframe revisits when an older keyframe, more than 5 s earlier, was within 15 cm and
#     20 degrees of it; it is found when an edge of the keyframe graph (any kind: odometry
#     against a reused keyframe, covisible or revisit alignment, map reuse, relocalisation)
#     joins it to a keyframe more than 5 s older. Recall = found / revisiting.
#   - every edge is checked against the ground truth's relative pose: more than 5 cm or 3
#     degrees off is a wrong edge. Precision = right edges / edges (odometry included; the
#     "edges" column counts those besides odometry).
#   - live ATE: every frame as reported; final map: every frame on its keyframe's final pose.
# Variants are made once into build/stress/ with build/bin/rgbdtam-stress; "no reuse" and
# "pool 9" are configurations that make loop closure do what map reuse would otherwise do.
#   tools/loop_recall.sh [--set key=value]...    (TUM data: ../shared/data/tum or RGBDTAM_TUM)
set -euo pipefail
cd "$(dirname "$0")/.."
bench=build/bin/rgbdtam-loop-bench
stress=build/bin/rgbdtam-stress
[ -x "$bench" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
[ -d "$tum/fr1_xyz" ] && [ -d "$tum/fr3_teddy_200" ] || { echo "no TUM data at $tum (set RGBDTAM_TUM)" >&2; exit 1; }
args=("$@")
cache=build/stress
mkdir -p "$cache"
make_variant() {
  local name=$1; shift
  [ -d "$cache/$name" ] && return 0
  "$@" >/dev/null || { rm -rf "$cache/$name"; echo "could not make $name" >&2; exit 1; }
}
fr1=config/tum_fr1.conf
fr3=config/tum_fr3.conf
make_variant xyz_blur30 "$stress" blur "$tum/fr1_xyz" "$cache/xyz_blur30" --config $fr1 --exposure-ms 30
make_variant xyz_x2 "$stress" decimate "$tum/fr1_xyz" "$cache/xyz_x2" 2
make_variant xyz_x2_blur30 "$stress" blur "$cache/xyz_x2" "$cache/xyz_x2_blur30" --config $fr1 --exposure-ms 30
make_variant xyz_there_and_back "$stress" there-and-back "$tum/fr1_xyz" "$cache/xyz_there_and_back" --config $fr1
make_variant xyz_there_and_back_blur30 "$stress" blur "$cache/xyz_there_and_back" "$cache/xyz_there_and_back_blur30" --config $fr1 --exposure-ms 30
make_variant xyz_twice "$stress" concat "$tum/fr1_xyz" "$cache/xyz_x2_blur30" "$cache/xyz_twice" --gap-s 1
make_variant teddy_blur20 "$stress" blur "$tum/fr3_teddy_200" "$cache/teddy_blur20" --config $fr3 --exposure-ms 20

rows=(
  "fr1_xyz|$tum/fr1_xyz|$fr1|"
  "fr3_teddy_200|$tum/fr3_teddy_200|$fr3|"
  "xyz blurred 30 ms|$cache/xyz_blur30|$fr1|"
  "xyz x2|$cache/xyz_x2|$fr1|"
  "xyz x2 blurred|$cache/xyz_x2_blur30|$fr1|"
  "xyz there and back|$cache/xyz_there_and_back|$fr1|"
  "xyz there and back, blurred|$cache/xyz_there_and_back_blur30|$fr1|"
  "xyz, then x2 blurred, 1 s apart|$cache/xyz_twice|$fr1|"
  "teddy blurred 20 ms|$cache/teddy_blur20|$fr3|"
  "xyz, pool 9|$tum/fr1_xyz|$fr1|map.keyframe_pool=9"
  "xyz blurred, pool 9|$cache/xyz_blur30|$fr1|map.keyframe_pool=9"
  "xyz x2 blurred, pool 9|$cache/xyz_x2_blur30|$fr1|map.keyframe_pool=9"
  "there and back blurred, pool 9|$cache/xyz_there_and_back_blur30|$fr1|map.keyframe_pool=9"
  "xyz, no reuse|$tum/fr1_xyz|$fr1|map.reuse_candidates=0"
  "xyz blurred, no reuse|$cache/xyz_blur30|$fr1|map.reuse_candidates=0"
  "there and back blurred, no reuse|$cache/xyz_there_and_back_blur30|$fr1|map.reuse_candidates=0"
)
echo "| sequence | keyframes | revisiting | found | recall | edges besides odometry | wrong edges | precision | live ATE cm | final-map ATE cm | coverage | false-valid |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
status=0
for row in "${rows[@]}"; do
  IFS='|' read -r name dir config set <<<"$row"
  extra=()
  [ -n "$set" ] && extra=(--set "$set")
  out=$("$bench" replay "$dir" --config "$config" "${extra[@]}" ${args[@]+"${args[@]}"} --row "$name") || status=$?
  printf '%s\n' "$out" | grep '^| '
done
exit $status
