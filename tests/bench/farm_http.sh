#!/usr/bin/env bash
# Tiny renders per second at C connections: rayfarmd alone, then the same rayfarmd as a
# one-node farm (--redis, its own redis-server on a unix socket), then a two-node farm behind
# no balancer (half the connections to each node). Same workers in all; every request is a
# new render (seeds differ).
#   tests/bench/farm_http.sh BUILD_DIR [connections = 32] [seconds = 10] [workers = 2]
set -euo pipefail
build=$(cd "$1" && pwd)
conns=${2:-32}; secs=${3:-10}; workers=${4:-2}
cd "$(dirname "$0")/../.."
dir=$(mktemp -d /tmp/rfload.XXXXXX)
pids=()
redis=""
cleanup() { for p in "${pids[@]}" $redis; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$dir"; }
trap cleanup EXIT
load="$build/tests/rayfarm_http_load"
start() {  # start PORT ARGS...: rayfarmd on PORT, waits for /healthz
  local port=$1; shift
  "$build/server/rayfarmd" --host 127.0.0.1 --port "$port" --no-access-log --workers "$workers" \
    --max-waiting-requests 256 --max-jobs-per-client 1000 "$@" >>"$dir/rayfarmd.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && return; sleep 0.05; done
  echo "rayfarmd did not start"; cat "$dir/rayfarmd.log"; exit 1
}
stop_all() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done; pids=(); }

echo "== rayfarmd alone"
start 18301
"$load" 127.0.0.1 18301 scenes/minimal.txt "$conns" "$secs"
stop_all

redis-server --port 0 --unixsocket "$dir/r.sock" --dir "$dir" --save "" --appendonly yes \
  --daemonize no >"$dir/redis.log" 2>&1 &
redis=$!
for _ in $(seq 100); do redis-cli -s "$dir/r.sock" ping 2>/dev/null | grep -q PONG && break; sleep 0.05; done
echo "== rayfarmd --redis (one node)"
start 18302 --redis "unix://$dir/r.sock" --node-id one
"$load" 127.0.0.1 18302 scenes/minimal.txt "$conns" "$secs"
stop_all
echo "== two nodes --redis, $((conns / 2)) connections each (on one machine: the same cores)"
start 18303 --redis "unix://$dir/r.sock" --node-id a
start 18304 --redis "unix://$dir/r.sock" --node-id b
"$load" 127.0.0.1 18303 scenes/minimal.txt "$((conns / 2))" "$secs" &
a=$!
"$load" 127.0.0.1 18304 scenes/minimal.txt "$((conns / 2))" "$secs"
wait "$a"
stop_all
kill "$redis"; wait "$redis" 2>/dev/null || true
