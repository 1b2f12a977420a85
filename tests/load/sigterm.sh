#!/usr/bin/env bash
# SIGTERM under load: work in flight finishes or is persisted, new work gets 503, the process
# exits 0, and after a restart every accepted job is done or runs again.
set -euo pipefail
source "$(dirname "$0")/common.sh"
dir=$(mktemp -d)
start_server --results-dir "$dir" --workers 2 --shutdown-grace 1
ids=()
for i in $(seq 12); do
  ids+=("$(curl -s --data-binary @scenes/cho.txt "http://127.0.0.1:$port/render?width=400&height=300&spp=16&seed=$i" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')")
done
kill -TERM "$pid"
sleep 0.2
during=$(curl -s -o /dev/null -w "%{http_code}" --data-binary @scenes/cho.txt "http://127.0.0.1:$port/render?width=40&height=30" || true)
wait "$pid"; code=$?
pid=""
echo "sigterm: exit code $code; a submission during shutdown got ${during:-no answer}"
start_server --results-dir "$dir" --workers 2
wait_for_states "done:12 " 120 "${ids[@]}"
echo "sigterm: after restart the 12 accepted jobs are: $states"
rm -rf "$dir"
[ "$code" = 0 ] && [[ "$during" == 503 || "$during" == 000 || -z "$during" ]] && [[ "$states" == "done:12 " ]] \
  && echo "sigterm: ok" || { echo "sigterm: FAIL"; exit 1; }
