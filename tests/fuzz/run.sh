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
  log="$build/fuzz-$target.log"
  (cd "$build" && ASAN_OPTIONS=detect_leaks=0 ./tests/fuzz/fuzz_$target -max_total_time="$seconds" \
     -timeout=10 -rss_limit_mb=4096 -max_len=65536 -print_final_stats=1 "corpus-$target") \
    >"$log" 2>&1 || status=$?
  grep -E "stat::number_of_executed_units|stat::peak_rss|Done" "$log" || true
  if [ "$status" != 0 ] || ls "$build"/crash-* "$build"/timeout-* "$build"/oom-* >/dev/null 2>&1; then
    # The whole report (the exception, the sanitizer's stack) and the input itself, so a
    # finding on a machine that is gone can still be replayed.
    echo "fuzzer $target failed (exit status $status); its report:"
    grep -v -E "^(INFO|#[0-9]+ +(NEW|REDUCE|pulse|RELOAD))" "$log" | tail -60
    for input in "$build"/crash-* "$build"/timeout-* "$build"/oom-*; do
      [ -e "$input" ] || continue
      echo "failing input $input, base64 (first 4 KB):"
      head -c 4096 "$input" | base64
    done
    exit 1
  fi
done
