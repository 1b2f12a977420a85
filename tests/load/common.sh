# Shared by the load scripts: start a rayfarmd on a free loopback port and stop it at exit.
# Sets $port and $pid; extra flags for rayfarmd come as arguments to start_server.
build=${BUILD:-build}
port=$((20000 + RANDOM % 12000))  # below the ephemeral range
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

# Polls the jobs named after the first two arguments until their states read EXPECTED
# ("done:8 ") or TIMEOUT seconds pass; leaves the last reading in $states.
wait_for_states() {
  local expected=$1 timeout=$2
  shift 2
  local deadline=$((SECONDS + timeout))
  states=""
  while [ $SECONDS -lt $deadline ]; do
    states=$(for id in "$@"; do curl -s "http://127.0.0.1:$port/jobs/$id" | python3 -c 'import json,sys; print(json.load(sys.stdin).get("state","missing"))'; done | sort | uniq -c | awk '{printf "%s:%s ", $2, $1}')
    [[ "$states" == "$expected" ]] && return 0
    sleep 0.5
  done
}
