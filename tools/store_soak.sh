#!/usr/bin/env bash
# Long runs at full stores: fr1_xyz wandered over (rgbdtam-stress wander: segments forwards and
# backwards at 1x and 2x, every fifth after an outage of 0.5-2 s somewhere else) and replayed
# with loop closure on, a place store of 256 and a dense pool of 9 (the stores scaled down so
# that one 26-second scene fills them many times over). Prints what the stores forgot, the
# stale handles refused, relocalisations at places older than the dense pool, resident memory,
# every loop correction and every graph edge against the ground truth (all frames).
#   tools/store_soak.sh [frames (60000)] [seed (7)]   (TUM data: ../shared/data/tum or RGBDTAM_TUM)
set -euo pipefail
cd "$(dirname "$0")/.."
frames=${1:-60000}
seed=${2:-7}
bench=build/bin/rgbdtam-loop-bench
stress=build/bin/rgbdtam-stress
[ -x "$bench" ] && [ -x "$stress" ] || { echo "build first: cmake --preset host-release && cmake --build --preset host-release" >&2; exit 1; }
tum=${RGBDTAM_TUM:-../shared/data/tum}
[ -d "$tum/fr1_xyz" ] || { echo "no TUM data at $tum (set RGBDTAM_TUM)" >&2; exit 1; }
mkdir -p build/stress
wander=build/stress/xyz_wander${frames}_seed$seed
[ -d "$wander" ] || "$stress" wander "$tum/fr1_xyz" "$wander" --config config/tum_fr1.conf \
  --frames "$frames" --seed "$seed"
start=$(date +%s)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
"$bench" replay "$wander" --config config/tum_fr1.conf --set loop.places=256 \
  --set map.keyframe_pool=9 > "$log" || status=$?
grep -v '^outage of' "$log"
# The outages, in one line: how the first valid pose after each came, and how late.
awk '/^outage of/ && /valid [0-9]+ frames/ { match($0, /valid [0-9]+/); f = substr($0, RSTART + 6, RLENGTH - 6) + 0; if (f > worst) worst = f }
     /^outage of/ { n++; if (/no valid pose/) none++; else { sub(/.*\(/, ""); sub(/\)/, ""); kind[$0]++ } }
     END { printf "outages: %d;", n; for (k in kind) printf " %s %d,", k, kind[k]; printf " never valid %d; at most %d frames to the first valid pose\n", none, worst }' "$log"
echo "replayed in $(( ($(date +%s) - start) / 60 )) min"
exit $status
