#!/usr/bin/env bash
# kill -9 in the middle of jobs, then restart: every accepted job has its result or runs again.
set -euo pipefail
source "$(dirname "$0")/common.sh"
dir=$(mktemp -d)
start_server --results-dir "$dir" --workers 2
ids=()
for i in $(seq 8); do
  ids+=("$(curl -s --data-binary @scenes/cho.txt "http://127.0.0.1:$port/render?width=400&height=300&spp=32&seed=$i" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')")
done
sleep 0.5
kill -9 "$pid"; wait "$pid" 2>/dev/null || true; pid=""
echo "kill9: killed with ${#ids[@]} jobs accepted"
start_server --results-dir "$dir" --workers 2
wait_for_states "done:8 " 180 "${ids[@]}"
echo "kill9: after restart: $states"
curl -s -o /tmp/kill9.png "http://127.0.0.1:$port/jobs/${ids[0]}/image"
"$build/client/rayfarm" render scenes/cho.txt --width 400 --height 300 --spp 32 --seed 1 -o /tmp/kill9-local.png -q
cmp -s /tmp/kill9.png /tmp/kill9-local.png && echo "kill9: the re-run image equals the local render" || { echo "kill9: FAIL: image differs"; exit 1; }
rm -rf "$dir"
[[ "$states" == "done:8 " ]] && echo "kill9: ok" || { echo "kill9: FAIL"; exit 1; }
