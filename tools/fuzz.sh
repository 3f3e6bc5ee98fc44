#!/usr/bin/env bash
# Fuzzes the MAVLink decoder with libFuzzer (Debian's clang) for N seconds (default 60),
# starting from a corpus of valid frames, and prints libFuzzer's summary (executions count).
#   tools/fuzz.sh [seconds]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
command -v clang++ >/dev/null || tools/setup.sh --fuzz
out=build/fuzz
mkdir -p "$out/corpus"
clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
  -Iinclude src/runtime/mavlink.cpp tests/fuzz/fuzz_mavlink_decoder.cpp -o "$out/fuzz_mavlink_decoder"
# Seeds: one frame of each message, so that the fuzzer starts past the checksum.
clang++ -std=c++17 -Iinclude src/runtime/mavlink.cpp tests/fuzz/make_seeds.cpp -o "$out/make_seeds"
"$out/make_seeds" "$out/corpus"
"$out/fuzz_mavlink_decoder" "$out/corpus" -max_total_time="$seconds" -print_final_stats=1 \
  -rss_limit_mb=1024 2>&1 | grep -E "^(Done|stat::number_of_executed_units|stat::peak_rss_mb|==|SUMMARY)|ERROR|crash" || true
test "${PIPESTATUS[0]}" -eq 0
