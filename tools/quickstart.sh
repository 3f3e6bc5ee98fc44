#!/usr/bin/env bash
# One command for a new machine: install the packages, build the static release binary and
# replay the committed real clip, printing the summary and the error against its ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh
cmake --preset host-release >/dev/null
cmake --build --preset host-release -j"$(nproc)" --target rgbdtam
build/bin/rgbdtam replay data/tum_fr1_xyz_clip --config config/tum_fr1.conf \
  --trajectory build/clip_trajectory.txt --map build/clip_map.ply
