#!/usr/bin/env bash
# The paper's residual-configuration table (Table "RMSE for different RGBDTAM configurations")
# for one sequence: one row per configuration, all-frames ATE. Tracking on sensor depth alone,
# as the paper's table compares the tracking residuals.
#   tools/ablation.sh <sequence-dir> [config]
set -euo pipefail
cd "$(dirname "$0")/.."
seq=${1:?usage: tools/ablation.sh <sequence-dir> [config]}
config=${2:-config/tum_fr1.conf}
first=--header
for r in PS PD GIDS GIDD 'GIDD*' PS+GIDD PS+GDD; do
  tools/bench.sh "$seq" "$config" $first --set "tracker.residuals=$r" --set map.enabled=false
  first=""
done
