#!/usr/bin/env bash
# Starts rayfarmd and runs slow_clients.py against it. Usage: tests/load/slow_clients.sh
set -euo pipefail
source "$(dirname "$0")/common.sh"
start_server
python3 "$(dirname "$0")/slow_clients.py" "$port" "${CLIENTS:-48}"
