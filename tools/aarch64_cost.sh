#!/usr/bin/env bash
# Instructions per frame of the aarch64 build's tracking path, counted under qemu-user without
# a plugin (its in_asm and exec logs, limited with -dfilter to the tracking functions), beside
# callgrind's count of the same functions in the host build, and a Cortex-A72 time estimate:
#   A72 ms = host ms x (aarch64 / host instructions) x (host instructions per second) /
#            (A72 instructions per second = IPC x 1.5 GHz),
# the host's rate measured here (callgrind's instructions per frame on the tracking path over its
# mean time per frame), for a stated range of the A72's sustained IPC.
#   tools/aarch64_cost.sh <sequence-dir> [config] [frames] [aarch64-build-dir]
# Builds first: build/bin/rgbdtam (host-release) and the aarch64 one (preset aarch64, in
# build/aarch64, or a board's, e.g. build/aarch64-raspberry-pi-4 with -mcpu=cortex-a72).
# Mapping and loop closure are off, so that only the tracker runs the counted functions; the
# count is the difference between a run of 2 + frames frames and one of 2 (init cancels out).
set -euo pipefail
cd "$(dirname "$0")/.."
seq=${1:?usage: tools/aarch64_cost.sh <sequence-dir> [config] [frames]}
config=${2:-config/tum_fr1.conf}
frames=${3:-40}
host=build/bin/rgbdtam
arm=${4:-build/aarch64}/bin/rgbdtam
for b in "$host" "$arm"; do [ -x "$b" ] || { echo "build $b first" >&2; exit 1; }; done
command -v qemu-aarch64 >/dev/null || { echo "qemu-aarch64 missing: tools/setup.sh --aarch64" >&2; exit 1; }
command -v valgrind >/dev/null || { echo "valgrind missing: tools/setup.sh --cost" >&2; exit 1; }
sysroot=/usr/aarch64-linux-gnu
# The tracking path's functions (the classes and the kernels of tracker.cpp and pyramid.cpp).
pattern='rgbdtam::(Tracker::|TrackingPipeline::|KeyframeBuilder::|CannyDetector::|FramePyramid::|Undistorter::|count_surface_pixels|compute_gradients|compute_depth_gradients|\(anonymous namespace\)::(add_normal_equations|project_points|geometric_residuals|weigh_rows|sum_padded|dot_lanes|downsample_gray|downsample_inverse_depth|central_differences))'
args=(replay "$(realpath "$seq")" --config "$(realpath "$config")" --quiet
      --set map.enabled=false --set loop.enabled=false)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

ranges=$(nm -C -S "$arm" | awk '$3 ~ /^[tTwW]$/' | grep -E "$pattern" |
         awk '{printf "%s0x%s+0x%s", (n++ ? "," : ""), $1, $2}')
arm_count() {  # instructions in the functions over a run of $1 frames
  qemu-aarch64 -L "$sysroot" -d in_asm,exec,nochain -dfilter "$ranges" "$arm" "${args[@]}" \
    --max-frames "$1" 2>&1 >/dev/null | awk -f tools/aarch64_cost/count_tb.awk | tail -1 |
    awk '{print $1}'
}
host_count() {
  valgrind --tool=callgrind --callgrind-out-file="$work/cg.$1" "$host" "${args[@]}" \
    --max-frames "$1" >/dev/null 2>&1
  callgrind_annotate --threshold=100 "$work/cg.$1" 2>/dev/null | grep -E "$pattern" |
    awk '{gsub(",", "", $1); s += $1} END {printf "%.0f\n", s}'
}
a0=$(arm_count 2); a1=$(arm_count $((2 + frames)))
h0=$(host_count 2); h1=$(host_count $((2 + frames)))
# The host's rate and time distribution on the default configuration (pose path only).
full=(replay "$(realpath "$seq")" --config "$(realpath "$config")" --quiet --max-frames 200)
valgrind --tool=callgrind --callgrind-out-file="$work/cg.path" \
  --toggle-collect='rgbdtam::TrackingPipeline::process(rgbdtam::SensorFrame const&)' \
  "$host" "${full[@]}" >/dev/null 2>&1
path=$(callgrind_annotate "$work/cg.path" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1}')
json=$("$host" "${full[@]}" --json 2>/dev/null)
field() { printf '%s' "$json" | sed -E "s/.*\"$1\": ([0-9.]+).*/\1/"; }
awk -v a="$((a1 - a0))" -v h="$((h1 - h0))" -v n="$frames" -v path="$path" \
    -v mean="$(field track_mean_ms)" -v median="$(field track_median_ms)" \
    -v p95="$(field track_p95_ms)" 'BEGIN {
  ratio = a / h
  printf "tracking functions, %d frames: aarch64 %.1f M instructions per frame, x86-64 %.1f M (ratio %.2f)\n", n, a / n / 1e6, h / n / 1e6, ratio
  rate = path / 200 / (mean * 1e-3)
  printf "host, first 200 frames: %.1f M instructions per frame on the pose path, mean %.2f ms: %.2f G instructions/s; median %.2f ms, p95 %.2f ms\n", path / 200 / 1e6, mean, rate / 1e9, median, p95
  for (ipc = 1.0; ipc <= 1.51; ipc += 0.25) {
    s = ratio * rate / (ipc * 1.5e9)
    printf "Cortex-A72 1.5 GHz at IPC %.2f: median %.1f ms, p95 %.1f ms per frame\n", ipc, median * s, p95 * s
  }
}'

# The cycle model. Every translated block of a group's functions goes through llvm-mca's
# Cortex-A72 scheduling model (the block's steady state when repeated, every load hitting L1 and
# every branch predicted: a lower bound on the cycles), weighted by how often qemu ran it; the
# difference of a run of 2 + frames frames and one of 2 leaves init out. Groups: the tracker's
# thread (the tracking functions above without the keyframe builder's) and the keyframe builder.
command -v llvm-mca >/dev/null && command -v llvm-mc >/dev/null ||
  { echo "llvm-mca missing: tools/setup.sh --cost" >&2; exit 1; }
builder_pattern='rgbdtam::(KeyframeBuildTask::|KeyframeBuilder::|CannyDetector::|compute_gradients|compute_depth_gradients)'
tracker_pattern=$(printf '%s' "$pattern" | sed -E 's/KeyframeBuilder::\||CannyDetector::\||compute_gradients\||compute_depth_gradients\|//g')
block_cycles() {  # $1: function pattern, $2: frames; prints "cycles instructions keyframes"
  local r
  r=$(nm -C -S "$arm" | awk '$3 ~ /^[tTwW]$/' | grep -E "$1" |
      awk '{printf "%s0x%s+0x%s", (n++ ? "," : ""), $1, $2}')
  qemu-aarch64 -L "$sysroot" -d in_asm,exec,nochain -dfilter "$r" "$arm" "${args[@]}" \
    --max-frames "$2" --json 2>&1 >"$work/json" | awk -f tools/aarch64_cost/tb_counts.awk > "$work/tb"
  # Each block between two markers (brk #0x4d43), disassembled in LLVM's syntax for llvm-mca.
  awk '{print "0x60 0xa8 0x29 0xd4"
        for (i = 3; i <= NF; i++) { w = $i
          printf "0x%s 0x%s 0x%s 0x%s\n", substr(w, 7, 2), substr(w, 5, 2), substr(w, 3, 2), substr(w, 1, 2) }}
       END {print "0x60 0xa8 0x29 0xd4"}' "$work/tb" |
    llvm-mc --disassemble -triple=aarch64 -mcpu=cortex-a72 /dev/stdin 2>/dev/null |
    awk '/brk\t#0x4d43/ {if (n) print "# LLVM-MCA-END"; n++; print "# LLVM-MCA-BEGIN tb" n; next}
         /\.text/ {next} {print}' | sed '$d' > "$work/tb.s"
  llvm-mca -mtriple=aarch64 -mcpu=cortex-a72 -iterations=100 "$work/tb.s" 2>/dev/null |
    awk '/Code Region - tb/ {id = substr($NF, 3)} /^Total Cycles:/ {print id, $3 / 100}' > "$work/cycles"
  local keyframes
  keyframes=$(sed -E 's/.*"keyframes": ([0-9]+).*/\1/' "$work/json")
  awk -v k="$keyframes" 'NR == FNR {c[$1] = $2; next}
       {cycles += $1 * c[FNR]; n += $1 * (NF - 2)} END {printf "%.0f %.0f %d\n", cycles, n, k}' \
    "$work/cycles" "$work/tb"
}
for group in tracker builder; do
  p=$tracker_pattern; [ "$group" = builder ] && p=$builder_pattern
  read -r c0 n0 k0 < <(block_cycles "$p" 2)
  read -r c1 n1 k1 < <(block_cycles "$p" $((2 + frames)))
  awk -v g="$group" -v c="$((c1 - c0))" -v n="$((n1 - n0))" -v f="$frames" -v k="$((k1 - k0))" 'BEGIN {
    if (g == "tracker") {
      printf "cycle model, tracker thread: %.1f M cycles per frame (%.1f M instructions, IPC %.2f): %.1f ms at 1.5 GHz, as a lower bound\n", c / f / 1e6, n / f / 1e6, n / c, c / f / 1.5e6
    } else if (k > 0) {
      printf "cycle model, keyframe builder: %.1f M cycles per keyframe (%d keyframes; %.1f M instructions, IPC %.2f): %.1f ms at 1.5 GHz, as a lower bound\n", c / k / 1e6, k, n / k / 1e6, n / c, c / k / 1.5e6
    }
  }'
done
