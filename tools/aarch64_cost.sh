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
# The modelled core: RGBDTAM_MCA_CPU (llvm-mca's -mcpu, default cortex-a72) at RGBDTAM_MCA_GHZ
# (default 1.5) with the llvm-mca RGBDTAM_MCA (default llvm-mca). LLVM schedules the Cortex-A72
# and the Cortex-A76 with one model, the Cortex-A57's; the Neoverse N1, the A76's server
# version (same core), has its own from LLVM 16: so a Raspberry Pi 5 is
# RGBDTAM_MCA=llvm-mca-19 RGBDTAM_MCA_CPU=neoverse-n1 RGBDTAM_MCA_GHZ=2.4.
# RGBDTAM_COST_PART=modules runs only the per-module cycle model (the second half).
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
mca=${RGBDTAM_MCA:-llvm-mca}
mca_flags=()  # a newer llvm-mca stops at an instruction its model lacks (an LSE atomic): skip it
"$mca" --help 2>/dev/null | grep -q skip-unsupported-instructions &&
  mca_flags=(-skip-unsupported-instructions=lack-sched)
mca_cpu=${RGBDTAM_MCA_CPU:-cortex-a72}
ghz=${RGBDTAM_MCA_GHZ:-1.5}
part=${RGBDTAM_COST_PART:-all}
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
if [ "$part" = all ]; then
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
    -v p95="$(field track_p95_ms)" -v cpu="$mca_cpu" -v ghz="$ghz" 'BEGIN {
  ratio = a / h
  printf "tracking functions, %d frames: aarch64 %.1f M instructions per frame, x86-64 %.1f M (ratio %.2f)\n", n, a / n / 1e6, h / n / 1e6, ratio
  rate = path / 200 / (mean * 1e-3)
  printf "host, first 200 frames: %.1f M instructions per frame on the pose path, mean %.2f ms: %.2f G instructions/s; median %.2f ms, p95 %.2f ms\n", path / 200 / 1e6, mean, rate / 1e9, median, p95
  for (ipc = 1.0; ipc <= 1.51; ipc += 0.25) {
    s = ratio * rate / (ipc * ghz * 1e9)
    printf "%s %.1f GHz at IPC %.2f: median %.1f ms, p95 %.1f ms per frame\n", cpu, ghz, ipc, median * s, p95 * s
  }
}'
fi

# The cycle model, per module. Every translated block qemu ran goes through llvm-mca's Cortex-A72
# scheduling model (the block's steady state when repeated, every load hitting L1 and every
# branch predicted: a lower bound on the cycles), weighted by how often it ran. A block is
# charged to the module whose step function ran last (tb_counts.awk), so helpers that several
# modules call go to their caller: the run is synchronous, the modules one after another on one
# thread. Mapping and loop closure are on; the difference of a run of 2 + frames frames and one
# of 2 leaves init out. The PNG decoder (libpng, zlib) is left out of the logs (a third of their
# volume; the sensor's cost is not modelled). Each module's host time over the same frames (the
# least of three traced replays) gives its A72 ratio, what tools/task_sim.py --scale takes.
command -v "$mca" >/dev/null && command -v llvm-mc >/dev/null ||
  { echo "llvm-mca missing: tools/setup.sh --cost" >&2; exit 1; }
module_args=(replay "$(realpath "$seq")" --config "$(realpath "$config")" --quiet
             --set map.threaded=false --set loop.threaded=false)
entries=$(paste -d' ' <(nm "$arm" | awk '{print $NF}') <(nm -C "$arm" | cut -d' ' -f3-) | awk '
  / rgbdtam::TrackingPipeline::process\(/ {print $1 "=tracker"}
  / rgbdtam::DepthInColour::apply\(/ {print $1 "=tracker"}
  / rgbdtam::KeyframeBuildTask::step\(/ {print $1 "=builder"}
  / rgbdtam::MappingModule::(step|finish)\(/ {print $1 "=mapper"}
  / rgbdtam::LoopModule::step\(/ {print $1 "=loop"}
  / rgbdtam::TumReplaySource::next\(/ {print $1 "=sensor"}' | tr '\n' ' ')
code=$(nm -n -S "$arm" | python3 -c '
import re, sys
decoder = re.compile(r"^(png_|_?inflate|adler32|crc32|updatewindow|zcalloc|zcfree|_tr_)")
ranges, start = [], None
for line in sys.stdin:
    f = line.split()
    if len(f) != 4 or f[2] not in "tTwW":
        continue
    a = int(f[0], 16)
    if decoder.match(f[3]):
        if start is not None:
            ranges.append((start, end))
        start = None
        continue
    start = a if start is None else start
    end = a + int(f[1], 16)
if start is not None:
    ranges.append((start, end))
print(",".join("0x%x+0x%x" % (a, b - a) for a, b in ranges))')
module_cycles() {  # $1: frames; prints "<module> <cycles> <instructions>" lines and "keyframes <n>",
  # and writes "<module> <cycles> <function>" lines to $work/fn.$1
  qemu-aarch64 -L "$sysroot" -d in_asm,exec,nochain -dfilter "$code" "$arm" "${module_args[@]}" \
    --max-frames "$1" --json 2>&1 >"$work/json" | awk -v entries="$entries" -f tools/aarch64_cost/tb_counts.awk |
    awk -v unique="$work/tb" '{key = $3; for (i = 4; i <= NF; i++) key = key " " $i
      if (!(key in id)) {id[key] = ++n; print NF - 3, key > unique}
      print $1, $2, id[key]}' > "$work/owned"
  # Each block between two markers (brk #0x4d43), disassembled in LLVM's syntax for llvm-mca.
  awk '{print "0x60 0xa8 0x29 0xd4"
        for (i = 3; i <= NF; i++) { w = $i
          printf "0x%s 0x%s 0x%s 0x%s\n", substr(w, 7, 2), substr(w, 5, 2), substr(w, 3, 2), substr(w, 1, 2) }}
       END {print "0x60 0xa8 0x29 0xd4"}' "$work/tb" |
    llvm-mc --disassemble -triple=aarch64 -mcpu="$mca_cpu" /dev/stdin 2>/dev/null |
    awk '/brk\t#0x4d43/ {if (n) print "# LLVM-MCA-END"; n++; print "# LLVM-MCA-BEGIN tb" n; next}
         /\.text/ {next} {print}' | sed '$d' > "$work/tb.s"
  "$mca" -mtriple=aarch64 -mcpu="$mca_cpu" "${mca_flags[@]}" -iterations=100 "$work/tb.s" 2>/dev/null |
    awk '/Code Region - tb/ {id = substr($NF, 3)} /^Total Cycles:/ {print id, $3 / 100}' > "$work/cycles"
  awk -v by_function="$work/fn.$1" '
       FILENAME == ARGV[1] {c[$1] = $2; next} FILENAME == ARGV[2] {size[FNR] = $1; sym[FNR] = $2; next}
       {cycles[$1] += $2 * c[$3]; n[$1] += $2 * size[$3]; f[$1 " " sym[$3]] += $2 * c[$3]}
       END {for (m in cycles) printf "%s %.0f %.0f\n", m, cycles[m], n[m]
            for (k in f) {split(k, mk, " "); printf "%s %.0f %s\n", mk[1], f[k], mk[2] > by_function}}' \
    "$work/cycles" "$work/tb" "$work/owned"
  echo "keyframes $(sed -E 's/.*"keyframes": ([0-9]+).*/\1/' "$work/json")"
}
module_cycles 2 > "$work/m0"
module_cycles $((2 + frames)) > "$work/m1"
for run in 1 2 3; do  # each module's host time over frames 3 .. 2 + frames, in ms
  "$host" "${module_args[@]}" --max-frames $((2 + frames)) --trace "$work/trace" >/dev/null 2>&1
  awk -F, 'NR > 3 {t += $3; b += $5; m += $7; l += $9}
           END {printf "tracker %.3f\nbuilder %.3f\nmapper %.3f\nloop %.3f\n", t / 1e6, b / 1e6, m / 1e6, l / 1e6}' \
    "$work/trace"
done > "$work/host"
awk -v f="$frames" -v cpu="$mca_cpu" -v ghz="$ghz" 'FILENAME == ARGV[1] {c0[$1] = $2; n0[$1] = $3; next}
     FILENAME == ARGV[2] {c1[$1] = $2; n1[$1] = $3; next}
     !($1 in host) || $2 < host[$1] {host[$1] = $2}
     END {
  k = c1["keyframes"] - c0["keyframes"]
  printf "cycle model, %s at %.1f GHz, %d frames, %d keyframes (lower bounds; host: this machine over the same frames):\n", cpu, ghz, f, k
  split("tracker builder mapper loop", order, " ")
  for (i = 1; i <= 4; i++) {
    m = order[i]; c = c1[m] - c0[m]; n = n1[m] - n0[m]
    per = (m == "tracker") ? f : k; unit = (m == "tracker") ? "frame" : "keyframe"
    if (per <= 0 || c <= 0) continue
    board_ms = c / per / (ghz * 1e6); h = host[m] / per
    printf "  %-8s %7.1f M cycles per %s (%.1f M instructions, IPC %.2f): %6.1f ms; host %5.2f ms, ratio %.2f\n", m, c / per / 1e6, unit, n / per / 1e6, n / c, board_ms, h, board_ms / h
    scale = scale sprintf("%s%s=%.2f", (scale == "" ? "" : ","), m, board_ms / h)
  }
  printf "tools/task_sim.py --scale %s\n", scale
}' "$work/m0" "$work/m1" "$work/host"
# Where each module's cycles go: its functions over the same frames (run of 2 + frames minus run
# of 2), the largest first, with what share of the module they are.
k=$(( $(awk '$1 == "keyframes" {print $2}' "$work/m1") - $(awk '$1 == "keyframes" {print $2}' "$work/m0") ))
echo "the largest functions of each module, M cycles per frame (tracker) or per keyframe (the rest):"
awk -v f="$frames" -v k="$k" 'FILENAME == ARGV[1] {c0[$1 " " $3] = $2; next}
     {d = $2 - c0[$1 " " $3]; if (d > 0) {fc[$1 " " $3] = d; total[$1] += d}}
     END {for (key in fc) {split(key, mk, " "); per = (mk[1] == "tracker") ? f : k
            if (per > 0) printf "%s %.2f %.0f %s\n", mk[1], fc[key] / per / 1e6, 100 * fc[key] / total[mk[1]], mk[2]}}' \
  "$work/fn.2" "$work/fn.$((2 + frames))" | c++filt |
  sed -E 's/\(anonymous namespace\)/{anonymous}/g; s/\(.*//' | sort -k1,1 -k2,2nr |
  awk '$1 != "-" && $1 != "sensor" && ++shown[$1] <= 8 {
         name = $0; sub(/^[^ ]+ [^ ]+ [^ ]+ /, "", name)
         printf "  %-8s %6.2f M %3d %%  %s\n", $1, $2, $3, name}'
