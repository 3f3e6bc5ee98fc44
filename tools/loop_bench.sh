#!/usr/bin/env bash
# Loop closure and relocalisation, the figures of the loop-closure issue (all frames unless
# said; false-valid as in rgbdtam eval; "final map" = every tracked frame placed on its keyframe
# as the map has it at the end, after every loop closure):
#   - kidnapping: fr1_xyz with frames 300.. cut (30, 60, 100, 150), with and without loop
#     closure, and with a vocabulary trained on fr3_teddy_200 alone (held out);
#   - a restart joined by a loop: the 100-frame cut without relocalisation;
#   - revisit: fr1_xyz forwards then backwards, with and without loop closure, and with map
#     reuse off so that loop closure has to do the work;
#   - place recognition's precision and recall on every sequence;
#   - costs: vocabulary, features, query, pose graph, memory.
#   tools/loop_bench.sh      (TUM data: ../shared/data/tum or RGBDTAM_TUM)
set -euo pipefail
cd "$(dirname "$0")/.."
bench=build/bin/rgbdtam-loop-bench
stress=build/bin/rgbdtam-stress
bin=build/bin/rgbdtam
[ -x "$bench" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
[ -d "$tum/fr1_xyz" ] && [ -d "$tum/fr3_teddy_200" ] || { echo "no TUM data at $tum (set RGBDTAM_TUM)" >&2; exit 1; }
cache=build/stress
mkdir -p "$cache"
for n in 30 60 100 150; do
  [ -d "$cache/xyz_cut$n" ] || "$stress" cut "$tum/fr1_xyz" "$cache/xyz_cut$n" 300 "$n" >/dev/null
done
[ -d "$cache/xyz_there_and_back" ] ||
  "$stress" there-and-back "$tum/fr1_xyz" "$cache/xyz_there_and_back" --config config/tum_fr1.conf >/dev/null
held_out=$cache/teddy-only.voc
[ -f "$held_out" ] ||
  "$bin" vocabulary train "$tum/fr3_teddy_200" --config config/tum_fr3.conf --out "$held_out" >/dev/null

run() {  # label sequence config [--set ...]
  local label=$1 seq=$2 config=$3; shift 3
  echo "## $label"
  "$bench" replay "$seq" --config "$config" "$@" | sed 's/^/    /'
}
for n in 30 60 100 150; do
  run "fr1_xyz, frames 300-$((299 + n)) cut: loop closure off" "$cache/xyz_cut$n" config/tum_fr1.conf --set loop.enabled=false
  run "fr1_xyz, frames 300-$((299 + n)) cut: loop closure on" "$cache/xyz_cut$n" config/tum_fr1.conf
  run "fr1_xyz, frames 300-$((299 + n)) cut: held-out vocabulary (fr3_teddy_200 only)" "$cache/xyz_cut$n" config/tum_fr1.conf --set "loop.vocabulary=$held_out"
done
run "fr1_xyz, frames 300-399 cut, no relocalisation: the restart joined by a loop" "$cache/xyz_cut100" config/tum_fr1.conf --set loop.relocalise=false
run "fr1_xyz there and back: loop closure off" "$cache/xyz_there_and_back" config/tum_fr1.conf --set loop.enabled=false
run "fr1_xyz there and back: loop closure on" "$cache/xyz_there_and_back" config/tum_fr1.conf
run "fr1_xyz there and back, no map reuse: loop closure off" "$cache/xyz_there_and_back" config/tum_fr1.conf --set loop.enabled=false --set map.reuse_candidates=0
run "fr1_xyz there and back, no map reuse: loop closure on" "$cache/xyz_there_and_back" config/tum_fr1.conf --set map.reuse_candidates=0
run "fr1_xyz" "$tum/fr1_xyz" config/tum_fr1.conf
run "fr1_xyz, no map reuse" "$tum/fr1_xyz" config/tum_fr1.conf --set map.reuse_candidates=0
run "fr3_teddy_200" "$tum/fr3_teddy_200" config/tum_fr3.conf
run "fr3_teddy_200, no map reuse" "$tum/fr3_teddy_200" config/tum_fr3.conf --set map.reuse_candidates=0
echo "## costs (this machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs))"
"$bench" costs "$tum/fr1_xyz" --config config/tum_fr1.conf | sed 's/^/    /'
