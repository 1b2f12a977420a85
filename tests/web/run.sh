#!/bin/sh
# The browser tests, as CTest runs them: tests/web/run.sh PATH/TO/rayfarmd
# Exits 77 (CTest's "skipped") when node, Debian's chromium or `npm ci --prefix tests/web`'s
# node_modules is missing, unless RAYFARM_REQUIRE_WEB_TESTS=1 (as .ci/run sets): CI must run them.
here=$(cd "$(dirname "$0")" && pwd)
RAYFARMD=${1:-$RAYFARMD}
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
export RAYFARMD CHROMIUM
missing=""
command -v node >/dev/null 2>&1 || missing="node (apt-get install nodejs)"
[ -x "$CHROMIUM" ] || missing="$missing $CHROMIUM (apt-get install chromium)"
[ -d "$here/node_modules/playwright-core" ] || missing="$missing tests/web/node_modules (npm ci --prefix tests/web)"
[ -x "$RAYFARMD" ] || missing="$missing rayfarmd (pass its path)"
if [ -n "$missing" ]; then
  echo "browser tests not run: missing$missing"
  [ "${RAYFARM_REQUIRE_WEB_TESTS:-0}" = 1 ] && exit 1
  exit 77
fi
# One file at a time: each starts its own rayfarmd and Chromium, and the machine has 2 cores.
exec node --test --test-concurrency=1 "$here"/*.test.mjs
