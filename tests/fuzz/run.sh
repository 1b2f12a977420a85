#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang and runs each for SECONDS (default 60), seeded
# with scenes/ and corpus/. A crash leaves its input in the fuzz build dir and fails the run;
# copy it into tests/fuzz/regressions/TARGET/ so every CI run replays it.
# Usage (from the repository root): tests/fuzz/run.sh [SECONDS]
set -euo pipefail
seconds=${1:-60}
build=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DRAYFARM_FUZZ=ON -DRAYFARM_BUILD_TESTS=OFF \
  -DRAYFARM_SANITIZE=fuzzer-no-link,address,undefined >/dev/null
cmake --build "$build" -j2 --target fuzz_model_parser fuzz_json_scene fuzz_image_decode fuzz_http_request
for target in model_parser json_scene image_decode http_request; do
  corpus="$build/corpus-$target"
  mkdir -p "$corpus"
  case $target in
    model_parser) cp scenes/*.txt scenes/extreme/*.txt "$corpus"/
      find tests/conformance/course -name "*.txt" -exec cp {} "$corpus"/ \; ;;
    json_scene) cp scenes/*.json "$corpus"/ 2>/dev/null || true ;;
    image_decode) cp tests/fuzz/corpus/image_decode/* "$corpus"/ ;;
    http_request) cp tests/fuzz/corpus/http_request/* "$corpus"/ ;;
  esac
  cp tests/fuzz/regressions/$target/* "$corpus"/ 2>/dev/null || true
  echo "fuzzing $target for ${seconds}s"
  # A finding makes the fuzzer exit non-zero: note it and name the input before failing.
  status=0
  (cd "$build" && ASAN_OPTIONS=detect_leaks=0 ./tests/fuzz/fuzz_$target -max_total_time="$seconds" \
     -timeout=10 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 "corpus-$target" \
     2>&1 | grep -E "stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY|crash-|timeout-|Done|fuzz property" | head -20) \
    || status=$?
  if [ "$status" != 0 ] || ls "$build"/crash-* "$build"/timeout-* "$build"/oom-* >/dev/null 2>&1; then
    echo "fuzzer $target failed (exit status $status); failing inputs:"
    ls "$build"/crash-* "$build"/timeout-* "$build"/oom-* 2>/dev/null || true
    exit 1
  fi
done
