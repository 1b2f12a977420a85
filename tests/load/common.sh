# Shared by the load scripts: start a rayfarmd on a free loopback port and stop it at exit.
# Sets $port and $pid; extra flags for rayfarmd come as arguments to start_server.
build=${BUILD:-build}
port=$((20000 + RANDOM % 20000))
pid=""

start_server() {
  "$build/server/rayfarmd" --host 127.0.0.1 --port "$port" --no-access-log "$@" \
    >>"${SERVER_LOG:-/tmp/rayfarmd-load.log}" 2>&1 &
  pid=$!
  for _ in $(seq 100); do
    curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && return 0
    sleep 0.05
  done
  echo "rayfarmd did not start"; exit 1
}

stop_server() {
  [ -n "$pid" ] && kill -TERM "$pid" 2>/dev/null && wait "$pid" 2>/dev/null || true
  pid=""
}
trap stop_server EXIT

rss_kb() { awk '/VmRSS/ {print $2}' "/proc/$1/status" 2>/dev/null || echo 0; }
