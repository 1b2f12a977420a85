#!/usr/bin/env bash
# A class submitting one scene at once: N students each POST the same render with wait=1, all
# at the same moment, against N renders of the same size that differ (a seed each, so that
# nothing is shared). Prints the wall time until the last answer of each, and how many jobs
# waited for a render under way (rayfarm_jobs_merged_total).
#   tests/bench/class_submit.sh [BUILD_DIR] [N]     (from the repository root; defaults build 40)
set -euo pipefail
build=${1:-build}
n=${2:-40}
BUILD=$build
source "$(dirname "$0")/../load/common.sh"
start_server --workers 2 --max-jobs-per-client 1000 --queue-capacity 1000 \
  --max-waiting-requests 1000
trap stop_server EXIT
url="http://127.0.0.1:$port/render?wait=1&width=400&height=300&spp=16"
run() {  # run SEED_OR_EMPTY_PER_JOB...: the wall time of all requests at once
  local t0=$EPOCHREALTIME
  printf '%s\n' "$@" | xargs -P "$n" -I{} curl -s -o /dev/null -w "%{http_code}\n" \
    --data-binary @scenes/cho.txt "$url{}" > /tmp/class-codes.txt
  awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.2f", b - a }'
}
same=() distinct=()
for i in $(seq "$n"); do same+=("&seed=100000"); distinct+=("&seed=$i"); done
t_same=$(run "${same[@]}")
codes_same=$(sort /tmp/class-codes.txt | uniq -c | awk '{printf "%s:%s ", $2, $1}')
merged=$(curl -s "http://127.0.0.1:$port/metrics" | awk '$1 == "rayfarm_jobs_merged_total" { print $2 }')
t_distinct=$(run "${distinct[@]}")
codes_distinct=$(sort /tmp/class-codes.txt | uniq -c | awk '{printf "%s:%s ", $2, $1}')
echo "class of $n, cho at 400x300 spp 16, 2 workers:"
echo "  the same render:   ${t_same} s (${codes_same}; ${merged} jobs waited for a render under way)"
echo "  distinct renders:  ${t_distinct} s (${codes_distinct})"
