#!/usr/bin/env bash
# All load and abuse scripts, loopback only, each bounded. Usage: tests/load/run_all.sh [BUILD]
set -uo pipefail
export BUILD=${1:-build}
here=$(dirname "$0")
status=0
for s in wrk_render.sh flood.sh slow_clients.sh sigterm.sh kill9.sh; do
  echo "=== $s"
  bash "$here/$s" "$BUILD" || status=1
done
exit $status
