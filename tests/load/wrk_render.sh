#!/usr/bin/env bash
# Throughput and latency of POST /render?wait=1 for a tiny render, at several connection
# counts, against a rayfarmd started here on a loopback port. Bounded: DURATION seconds per
# run. Usage: tests/load/wrk_render.sh [BUILD_DIR] (from the repository root).
set -euo pipefail
build=${1:-${BUILD:-build}}
duration=${DURATION:-10}
connections=${CONNECTIONS:-"8 32 64"}
port=$((20000 + RANDOM % 12000))  # below the ephemeral range
command -v wrk >/dev/null || { echo "wrk is not installed (apt-get install wrk)"; exit 1; }

"$build/server/rayfarmd" --host 127.0.0.1 --port "$port" --no-access-log \
  --queue-capacity 4096 --max-jobs-per-client 4096 --max-waiting-requests 128 --http-threads 160 \
  >/tmp/rayfarmd-load.log 2>&1 &
pid=$!
trap 'kill -TERM $pid 2>/dev/null; wait $pid 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && break; sleep 0.1; done

here=$(dirname "$0")
echo "rayfarmd on 127.0.0.1:$port, $(nproc) cores; POST /render?wait=1, 40x30 lecture scene"
for c in $connections; do
  # miss: every request has its own seed, so each one renders; hit: all the same request.
  for cache in miss hit; do
    vary=0; [ "$cache" = miss ] && vary=1
    echo "--- $c connections, cache $cache"
    WRK_SCENE=scenes/cho.txt WRK_QUERY="width=40&height=30&wait=1" WRK_VARY=$vary \
      wrk -t2 -c"$c" -d"${duration}s" --timeout 10s -s "$here/render.lua" "http://127.0.0.1:$port" \
      | grep -E "statuses|latency_ms|requests_per_second"
  done
done
