#!/usr/bin/env bash
# Submission faster than the server can render: every answer must be 202 or 429, and the
# server's memory must stay bounded. Usage: tests/load/flood.sh (from the repository root).
set -euo pipefail
source "$(dirname "$0")/common.sh"
requests=${REQUESTS:-2000}
start_server --queue-capacity 64 --max-jobs-per-client 64 --workers 2
rss_before=$(rss_kb "$pid")
# 8 parallel submitters of a 200x150 spp-4 render, each request distinct (no cache hits).
seq "$requests" | xargs -P 8 -I{} curl -s -o /dev/null -w "%{http_code}\n" \
  --data-binary @scenes/cho.txt "http://127.0.0.1:$port/render?width=200&height=150&spp=4&seed={}" \
  > /tmp/flood-codes.txt
rss_after=$(rss_kb "$pid")
health_ms=$(curl -s -o /dev/null -w "%{time_total}" "http://127.0.0.1:$port/healthz" | awk '{printf "%.1f", $1*1000}')
echo "flood: $requests submissions, 8 at a time: $(sort /tmp/flood-codes.txt | uniq -c | awk '{printf "%s:%s ", $2, $1}')"
echo "flood: rss before ${rss_before} kB, after ${rss_after} kB; /healthz during backlog ${health_ms} ms"
bad=$(grep -cvE '^(202|429)$' /tmp/flood-codes.txt || true)
[ "$bad" = 0 ] || { echo "flood: FAIL: $bad answers other than 202/429"; exit 1; }
[ "$rss_after" -lt $((rss_before + 400000)) ] || { echo "flood: FAIL: memory grew by more than 400 MB"; exit 1; }
echo "flood: ok"
