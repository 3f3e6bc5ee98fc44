#!/usr/bin/env bash
# The test command: host release build and the live page in headless Chromium; host debug build
# under ASan+UBSan with the shared-library sensor backends, and every test but the long ones; the
# release build's other tests (the full fr1_xyz ones run where the sequence exists); each board's
# own firmware build (the Raspberry Pi 4's static one runs the whole aarch64 suite under qemu-user
# through the HIL runner's stand-in transport; the Raspberry Pi 5's static V4L2 one and the ROCK
# 5B's dynamic OpenNI2 one run their board and firmware tests); and a short fuzzing run of every
# parser.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup.sh --aarch64 --fuzz --opencv --browser
jobs=$(nproc)
logs=$(mktemp -d)

# Every preset configured at once (configuring is mostly one core's work). No compiler cache:
# the two aarch64 boards are tuned for different cores (-mcpu), so they share no object.
# Nothing runs beside the builds and test runs: on this 2-core machine the aarch64 set-up beside
# the host build, even at the lowest priority, cost the build (or the test runs) more than it
# saved.
echo "=== configure every preset ($(date +%T))"
pids=()
for preset in host-release host-debug aarch64-raspberry-pi-4 aarch64-raspberry-pi-5 \
  aarch64-radxa-rock-5b; do
  cmake --preset "$preset" >"$logs/configure-$preset.log" 2>&1 &
  pids+=($!)
done
for pid in "${pids[@]}"; do
  wait "$pid" || { tail -n 30 "$logs"/configure-*.log; exit 1; }
done

# build PRESET [TARGET...]: all targets unless named.
build() {
  local preset=$1; shift
  echo "=== $preset: build ($(date +%T))"
  local targets=()
  for t in "$@"; do targets+=(--target "$t"); done
  if ! cmake --build --preset "$preset" -j"$jobs" "${targets[@]}" >"$logs/build-$preset.log" 2>&1; then
    tail -n 60 "$logs/build-$preset.log"
    exit 1
  fi
}
check() {
  local preset=$1; shift
  echo "=== $preset: test ($(date +%T))"
  ctest --preset "$preset" -j"$jobs" "$@"
}

# All but the test binaries whose every test the sanitizer build runs (SAME_IN_EVERY_BUILD in
# tests/CMakeLists.txt): the release build would compile them for nothing.
build host-release rgbdtam-all-but-tests-the-sanitizers-run
file build/bin/rgbdtam | grep -q "statically linked" || { echo "host rgbdtam is not static" >&2; exit 1; }
echo "=== node-mavlink: the link as an independent decoder sees it ($(date +%T))"
node tools/mavlink-check/check.mjs build/bin/rgbdtam board/host-emulation
build/bin/rgbdtam-stress wall "$logs/wall" --distance-m 2 --yaw-deg 20 --frames 30 >/dev/null
node tools/mavlink-check/obstacle-check.mjs build/bin/rgbdtam board/host-emulation "$logs/wall" 2 20
node tools/mavlink-check/autopilot-check.mjs build/bin/rgbdtam board/host-emulation "$PWD/data/tum_fr1_xyz_clip"
echo "=== the task-table simulator: hand-checked traces, then the clip's trace ($(date +%T))"
python3 tools/task_sim_test.py build/bin/rgbdtam
build/bin/rgbdtam replay data/tum_fr1_xyz_clip --config config/tum_fr1.conf --quiet \
  --trace "$logs/clip-trace.csv" >/dev/null
python3 tools/task_sim.py "$logs/clip-trace.csv" --board board/host-emulation | tee "$logs/clip-sim.txt"
grep -q "^deadline misses 0, dropped frames 0" "$logs/clip-sim.txt"
echo "=== the monitor's live page in headless Chromium ($(date +%T))"
node tools/mavlink-check/page-check.mjs build/bin board/host-emulation build/monitor-page
# With the shared-library backends: Debian's libfreenect against its fakenect, OpenNI2's Dummy
# device; it also compiles rgbdtam-vs-opencv (the host-dynamic preset's benchmark).
build host-debug
check host-debug -LE long
# The release build runs the tests the sanitizer build did not: the long ones and those built
# only here (allocation counts, the tools'). The others ran just above (their binaries, not built
# here, are listed as NOT_BUILT), and again as release code on the Raspberry Pi 4's build under
# qemu below.
ran_in_debug=$(ctest --preset host-debug -N -LE long | sed -n 's/^ *Test *#[0-9]*: //p')
release_only=$(ctest --preset host-release -N | sed -n 's/^ *Test *#\([0-9]*\): /\1 /p' |
  awk 'NR == FNR { ran[$0] = 1; next }
       { n = $1; sub(/^[0-9]+ /, ""); if (!($0 in ran) && $0 !~ /_NOT_BUILT$/) print n }' \
    <(echo "$ran_in_debug") - | paste -sd,)
check host-release -I "0,0,0,$release_only"
# Raspberry Pi 4: static, Kinect v1; its whole suite under qemu through the HIL runner, but for
# the allocation counts (the same code's counts ran natively above, as release code: emulation
# changes none of them and took them from seconds to a minute and a half; their binary is not
# even built here, where it cost 15 s of compiling), the rendered pans tracked end to end and a
# restart's keyframe rows (pipeline logic, no arithmetic of its own; the rolling shutter's rows
# are tracked under qemu by RollingShutter.*), nine end-to-end
# replays of half a minute or more under emulation (natively seconds; the code they run is run
# under qemu by the other tests, such as RealClip's, the kidnapped frame's, the fakenect dump's
# frame-exact test and the map file's damage test), the scripted autopilot's 50 frames (each
# waited for: slow under emulation) and the place store's 30 keyframes (each waited for until
# built, and described: a minute under emulation): they run in the host suites, and everything
# on the board itself.
build aarch64-raspberry-pi-4 rgbdtam \
  $(awk '$1 != "test_allocations" { print $1 }' build/aarch64-raspberry-pi-4/hil-tests.txt)
tools/hil/run.py raspberry-pi-4 qemu: --skip '^('\
'RobustTracking\.(TheAutopilotsTurnIsTheFirstGuessAndAWrongOneIsRefused|AFastPanIsTrackedOrLostNeverWrong|'\
'ARollingShuttersRowsAreTrackedFromTheirOwnInstants|AKeyframeMadeAtARestartIsPlacedAsIfStill)|'\
'Freenect\.TheFirmwareOnAKinectDumpStreamsThePosesOfTheTumReplayOfItsFrames|'\
'RepeatedScenes\.(PanelsAt10HzAfterALossAreNeverWrong|BrickAt10HzWithAReadoutItDoesNotHaveIsNeverWrong)|'\
'MapFile\.(ASecondSessionIsFoundInTheFirstOnesMapAndReportsPosesInItsWorld|'\
'LocaliseModeKeepsTheMapsPlacesWhereTheyWere|AWriterKilledAtAnyInstantLeavesAMapThatLoads)|'\
'Firmware\.(TheAutopilotsAttitudeLevelsTheOdometryFrameAndGuidesTheTracker|'\
'ThePlaceStoreFillingIsReportedOnceAndCounted|RegistrationOnTheSensorsThreadTracksAsOnTheTrackers))'
file build/aarch64-raspberry-pi-4/bin/rgbdtam | grep -q "ARM aarch64.*statically linked" \
  || { echo "the Raspberry Pi 4's rgbdtam is not a static ARM binary" >&2; exit 1; }
# The runner's SSH transport, to an sshd on loopback that runs the binaries under qemu, beside
# the next build (it is mostly waiting on one core).
tools/hil/ssh_loopback_check.sh raspberry-pi-4 >"$logs/ssh.log" 2>&1 &
ssh_check=$!
# Raspberry Pi 5: static, a RealSense D435 over V4L2. The code its suite would run is the Pi 4's
# but for -mcpu (the whole suite runs under qemu above), so qemu runs its board and firmware
# tests: the whole suite again would take CI past its time.
build aarch64-raspberry-pi-5 rgbdtam
check aarch64-raspberry-pi-5 -R '^(BoardBuild|Firmware)\.'
file build/aarch64-raspberry-pi-5/bin/rgbdtam | grep -q "ARM aarch64.*statically linked" \
  || { echo "the Raspberry Pi 5's rgbdtam is not a static ARM binary" >&2; exit 1; }
# Radxa ROCK 5B: dynamic for OpenNI2's driver plugins. qemu runs its board and firmware tests;
# OpenNI2's initialise hangs under qemu-user, so the Xtion itself is a hardware test.
build aarch64-radxa-rock-5b rgbdtam
check aarch64-radxa-rock-5b -R '^(BoardBuild|Firmware)\.'
ssh_ok=true
wait "$ssh_check" || ssh_ok=false
cat "$logs/ssh.log"
$ssh_ok || exit 1
echo "=== fuzz: every parser, briefly ($(date +%T))"
FUZZ_OPT=-O0 tools/fuzz.sh 5
echo "=== each board's firmware"
for board in host-emulation raspberry-pi-4 raspberry-pi-5 radxa-rock-5b; do
  preset=$(sed -n 's/^build\.preset *= *//p' "board/$board/board.conf")
  dir=build
  [ "$preset" = host-release ] || dir=build/$preset
  echo "$board ($preset): $(file -b "$dir/bin/rgbdtam" | cut -d, -f1-2,4)"
  # Run as its tests run (under qemu when cross-built).
  ctest --preset "$preset" -R '^BoardBuild\.TheVersion' -V | sed -n 's/^[0-9]*: \(rgbdtam [0-9].*\)/  \1/p'
  # Assertion messages and debug info name files relative to the repository.
  if grep -q -a -F "$PWD/" "$dir/bin/rgbdtam"; then
    echo "$dir/bin/rgbdtam names this machine's folder $PWD" >&2
    exit 1
  fi
done
