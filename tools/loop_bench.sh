#!/usr/bin/env bash
# Loop closure and relocalisation, the figures of docs/loop-closure.md (all frames unless said;
# false-valid as in rgbdtam eval; "final map" = every tracked frame placed on its keyframe as the
# map has it at the end, after every correction):
#   - kidnapping: fr1_xyz with 30, 60, 100 and 150 frames cut at frames 150, 300, 450 and 600:
#     how many frames after the gap the first valid pose came, and how (relocalised, tracked);
#   - a restart joined by a revisit: 150 frames cut at 150 without relocalisation;
#   - place recognition by appearance alone, with the shipped vocabulary and with one trained
#     without fr1_xyz (held out);
#   - costs: vocabulary, features, query, view alignment, pose graph, memory.
# The revisit table (recall and precision of the keyframe graph's edges) is tools/loop_recall.sh.
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
fr1=config/tum_fr1.conf
for at in 150 300 450 600; do
  for n in 30 60 100 150; do
    [ -d "$cache/xyz_cut${at}_$n" ] || "$stress" cut "$tum/fr1_xyz" "$cache/xyz_cut${at}_$n" "$at" "$n" >/dev/null
  done
done
[ -d "$cache/xyz_blur30" ] ||
  "$stress" blur "$tum/fr1_xyz" "$cache/xyz_blur30" --config $fr1 --exposure-ms 30 >/dev/null
held_out=$cache/without-fr1_xyz.voc
[ -f "$held_out" ] || {
  [ -d "$cache/pan90" ] || "$stress" pan "$cache/pan90" --peak-deg-s 90 >/dev/null
  [ -d "$cache/plain_room" ] || "$stress" degenerate "$cache/plain_room" --scene room --frames 188 >/dev/null
  "$bin" vocabulary train "$tum/fr3_teddy_200" "$cache/pan90" "$cache/plain_room" --config $fr1 \
    --every 3 --augment --out "$held_out" >/dev/null
}

echo "## kidnapping: fr1_xyz with frames cut (loop closure off: ATE; on: ATE, coverage, false-valid, the first valid pose after the gap)"
echo "| cut | loop off: ATE cm | loop on: ATE cm | coverage | false-valid | after the gap |"
echo "|---|---|---|---|---|---|"
for at in 150 300 450 600; do
  for n in 30 60 100 150; do
    seq=$cache/xyz_cut${at}_$n
    off=$("$bench" replay "$seq" --config $fr1 --set loop.enabled=false | sed -n 's/^live: ATE \([0-9.]*\) cm.*/\1/p')
    on=$("$bench" replay "$seq" --config $fr1)
    live=$(printf '%s\n' "$on" | grep '^live:')
    gap=$(printf '%s\n' "$on" | sed -n 's/^outage of [0-9.]* s: //p')
    printf '| %d at %d | %s | %s | %s | %s | %s |\n' "$n" "$at" "$off" \
      "$(printf '%s' "$live" | sed 's/^live: ATE \([0-9.]*\) cm.*/\1/')" \
      "$(printf '%s' "$live" | sed 's/.*coverage \([0-9.]* %\).*/\1/')" \
      "$(printf '%s' "$live" | sed 's/.*false-valid \([0-9]* of [0-9]*\);.*/\1/')" "$gap"
  done
done
echo "## fr1_xyz, 150 frames cut at 150, no relocalisation: the restart joined by a revisit"
"$bench" replay "$cache/xyz_cut150_150" --config $fr1 --set loop.relocalise=false | grep -v '^  wrong' | sed 's/^/    /'
echo "## place recognition by appearance alone (recall of revisits among the best places)"
for voc in "$(sed -n 's/^loop.vocabulary *= *//p' $fr1 | cut -d' ' -f1)" "$held_out"; do
  for seq in "$tum/fr1_xyz" "$cache/xyz_blur30"; do
    path=$voc
    [ "${path#/}" = "$path" ] && [ "$voc" != "$held_out" ] && path=$PWD/config/$voc
    "$bench" bow "$seq" --config $fr1 --set "loop.vocabulary=$path" | sed "s|$PWD/||g; s|config/\.\./||g; s/^/    /"
  done
done
echo "## costs (this machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs))"
"$bench" costs "$tum/fr1_xyz" --config $fr1 | sed 's/^/    /'
