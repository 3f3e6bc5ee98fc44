#!/usr/bin/env bash
# Fuzzes every parser with libFuzzer (Debian's clang) under AddressSanitizer and UBSan, N
# seconds each (default 60), from seed corpora, and prints each target's executions:
#   mavlink_decoder  the MAVLink decoder the link runs (arbitrary bytes in arbitrary chunks)
#   png_decoder      PNG decoding through our arena, as grey and as depth (libpng and zlib are
#                    Debian's uninstrumented builds: guidance covers our code, ASan all of it)
#   text_formats     TUM lists, configs, boards, --set/--board-set values, trajectories
#   map_file         map files, as replay and run load them and as the exporters read them
#   tools/fuzz.sh [seconds] [target...]
# FUZZ_OPT (default -O1) is the optimisation: CI's run of a few seconds a target builds at -O0,
# in two thirds of the time, where the build and not the executions is the run's cost.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(mavlink_decoder png_decoder text_formats map_file)
command -v clang++ >/dev/null || tools/setup.sh --fuzz
out=build/fuzz
mkdir -p "$out"
# Line tables only: all that the sanitizers' reports use (a fifth less compile time than -g).
flags=(-std=c++17 -gline-tables-only "${FUZZ_OPT:--O1}" -fsanitize=fuzzer,address,undefined
       -fno-sanitize-recover=all -Iinclude -isystem /usr/include/eigen3)

# Each folder's sources are compiled as units of up to eight files (as the CMake build's unity
# batches: Eigen's templates instantiated once per unit, and the units of a target compiled side
# by side), shared by the targets of one run, never across runs.
rm -rf "$out/obj"
mkdir -p "$out/obj"
build() {  # name, sources... (the units not yet compiled, in parallel, then linked)
  local name=$1 objects=() missing=() dir files part unit chunks i j
  shift
  for dir in $(printf '%s\n' "$@" | xargs -n1 dirname | sort -u); do
    files=()
    for src in "$@"; do [ "$(dirname "$src")" != "$dir" ] || files+=("$PWD/$src"); done
    chunks=$(((${#files[@]} + 7) / 8))
    for ((i = 0; i < chunks; i++)); do
      part=()
      for ((j = i; j < ${#files[@]}; j += chunks)); do part+=("${files[j]}"); done
      unit="$out/obj/$(echo "$dir" | tr / _)_$(printf '%s\n' "${part[@]}" | md5sum | cut -c1-12)"
      objects+=("$unit.o")
      [ -f "$unit.o" ] && continue
      printf '#include "%s"\n' "${part[@]}" >"$unit.cpp"
      missing+=("$unit")
    done
  done
  [ ${#missing[@]} -eq 0 ] || printf '%s\n' "${missing[@]}" | xargs -P "$(nproc)" -I{} sh -c \
    'clang++ "$@" -c {}.cpp -o {}.o' _ "${flags[@]}"
  clang++ "${flags[@]}" "${objects[@]}" -lpng -lz -o "$out/fuzz_$name"
}

seed_mavlink_decoder() {
  clang++ -std=c++17 -Iinclude src/runtime/mavlink.cpp tests/fuzz/make_seeds.cpp -o "$out/make_seeds"
  "$out/make_seeds" "$1"
}
seed_png_decoder() { cp tests/fuzz/seeds/png/* "$1"/; }
seed_text_formats() {  # the first byte chooses the format (fuzz_text_formats.cpp)
  local n=0
  for entry in 0:data/tum_fr1_xyz_clip/rgb.txt 0:data/tum_fr1_xyz_clip/depth.txt \
      1:config/tum_fr1.conf 1:config/kinect_v1.conf 2:board/host-emulation/board.conf \
      2:board/raspberry-pi-4/board.conf 3:data/tum_fr1_xyz_clip/groundtruth.txt; do
    { printf "\\x0${entry%%:*}"; head -c 4000 "${entry#*:}"; } >"$1/seed$((n++))"
  done
  printf '\x04tracker.robust_c=3' >"$1/seed$n"
}

seed_map_file() { RGBDTAM_WRITE_MAP_SEEDS="$1" "$out/fuzz_map_file"; }

fuzzers=()
for t in "${targets[@]}"; do
  case $t in
    mavlink_decoder) build "$t" src/runtime/mavlink.cpp tests/fuzz/fuzz_mavlink_decoder.cpp ;;
    png_decoder) build "$t" src/hal/png_decoder.cpp tests/fuzz/fuzz_png_decoder.cpp ;;
    text_formats)
      build "$t" src/core/assert.cpp src/core/residuals.cpp src/hal/tum_replay_source.cpp src/hal/tum_trajectory.cpp \
        src/hal/tum_timestamp.cpp src/hal/file.cpp src/hal/clock.cpp src/hal/png_decoder.cpp src/port/messages.cpp \
        src/runtime/board.cpp src/runtime/params.cpp src/runtime/key_value.cpp \
        tests/fuzz/fuzz_text_formats.cpp ;;
    map_file)
      build "$t" src/core/{assert,camera,canny,features,keyframe_builder,kth_smallest,place_database}.cpp \
        src/core/{pose_graph,pyramid,residuals,rigid_alignment,se3,symmetric_eigen,tracker,tracking_health}.cpp \
        src/core/{view_alignment,vocabulary}.cpp src/runtime/map_file.cpp src/runtime/place_recognition.cpp \
        src/runtime/loop_closing.cpp src/runtime/map_checkpoint.cpp src/runtime/params.cpp \
        src/runtime/key_value.cpp src/port/{latency_stats,messages}.cpp tests/fuzz/fuzz_map_file.cpp ;;
    *) echo "unknown fuzz target $t" >&2; exit 2 ;;
  esac
  corpus="$out/corpus_$t"
  mkdir -p "$corpus"
  "seed_$t" "$corpus"
  # Fuzzes while the next target builds; the reports follow, in order.
  "$out/fuzz_$t" "$corpus" -max_total_time="$seconds" -print_final_stats=1 -rss_limit_mb=2048 \
    -max_len=8192 >"$out/log_$t" 2>&1 &
  fuzzers+=("$t:$!")
done
failed=0
for entry in "${fuzzers[@]}"; do
  t=${entry%%:*}
  status=0
  wait "${entry#*:}" || status=$?
  echo "--- $t ($seconds s)"
  grep -E "^(Done|stat::number_of_executed_units|==|SUMMARY)|ERROR|crash" "$out/log_$t" || true
  [ "$status" -eq 0 ] || failed=1
done
exit "$failed"
