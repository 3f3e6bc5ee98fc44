#!/usr/bin/env bash
# The test command: host release build with every test (the full fr1_xyz test runs where the
# sequence exists), host debug build under ASan+UBSan, the dynamic build with the shared-library
# sensor backends, and the static aarch64 build with its
# tests under qemu-user, a build for each board's CPU, and a short fuzzing run of every parser.
# The slow full-sequence test is left to the release build.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh --aarch64 --fuzz --opencv
jobs=$(nproc)

run() {
  local preset=$1; shift
  echo "=== $preset: configure and build ($(date +%T))"
  cmake --preset "$preset" >/dev/null
  local log
  log=$(mktemp)
  if ! cmake --build --preset "$preset" -j"$jobs" >"$log" 2>&1; then
    tail -n 60 "$log"
    exit 1
  fi
  echo "=== $preset: test ($(date +%T))"
  ctest --preset "$preset" -j"$jobs" "$@"
}

run host-release
file build/bin/rgbdtam | grep -q "statically linked" || { echo "host rgbdtam is not static" >&2; exit 1; }
echo "=== node-mavlink: the link as an independent decoder sees it ($(date +%T))"
node tools/mavlink-check/check.mjs build/bin/rgbdtam board/host-emulation
run host-debug -LE long
# The shared-library sensor backends (libfreenect, tested against fakenect).
run host-dynamic -LE long
run aarch64 -LE long
file build/aarch64/bin/rgbdtam | grep -q "ARM aarch64.*statically linked" \
  || { echo "aarch64 rgbdtam is not a static ARM binary" >&2; exit 1; }
# Each board's CPU flags compile the core (where they matter); the full firmware is the
# aarch64 build above.
for board in raspberry-pi-4 radxa-rock-5b; do
  echo "=== aarch64-$board: build the core with the board's -mcpu ($(date +%T))"
  cmake --preset "aarch64-$board" >/dev/null
  cmake --build --preset "aarch64-$board" -j"$jobs" --target rgbdtam_core >/dev/null
done
echo "=== fuzz: every parser, briefly ($(date +%T))"
tools/fuzz.sh 10
echo "=== static binaries"
file build/bin/rgbdtam build/aarch64/bin/rgbdtam
