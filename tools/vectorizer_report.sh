#!/usr/bin/env bash
# GCC's vectoriser report for the tracking path's loops, for the portable host build (SSE2) and
# for aarch64 with a board's -mcpu (NEON): each loop it vectorised, with its source line.
#   tools/vectorizer_report.sh [cortex-a72]
set -euo pipefail
cd "$(dirname "$0")/.."
cpu=${1:-cortex-a72}
files=(src/core/tracker.cpp src/core/pyramid.cpp src/core/camera.cpp)
flags=(-std=c++17 -O3 -DNDEBUG -fno-exceptions -fno-rtti -fno-trapping-math -Iinclude
       -isystem /usr/include/eigen3)
report() {  # compiler, extra flags...
  local cxx=$1; shift
  for f in "${files[@]}"; do
    "$cxx" "${flags[@]}" "$@" -c "$f" -o /dev/null -fopt-info-vec-optimized 2>&1 |
      grep "loop vectorized" | grep -v "/usr/include" | sort -u -t: -k1,2 |
      while IFS=: read -r file line _ rest; do
        printf '  %s:%s: %s\n    %s\n' "$file" "$line" "${rest# }" "$(sed -n "${line}p" "$file" | sed 's/^ *//')"
      done
  done
}
echo "x86-64 (portable: SSE2, no -march):"
report g++
if command -v aarch64-linux-gnu-g++ >/dev/null; then
  echo "aarch64 -mcpu=$cpu (NEON):"
  report aarch64-linux-gnu-g++ "-mcpu=$cpu"
fi
