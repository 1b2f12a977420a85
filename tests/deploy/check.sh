#!/usr/bin/env bash
# The deployment files parse and work as shipped: both nginx configs pass `nginx -t` and proxy
# a render, server-sent events and the TLS redirect to a real rayfarmd; the systemd unit passes
# `systemd-analyze verify`. Exit 77 (skipped) without nginx.
# Usage: tests/deploy/check.sh BUILD_DIR
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="$(cd "${1:?build dir}" && pwd)"
command -v nginx >/dev/null || { echo "nginx is not installed: skipped"; exit 77; }
command -v openssl >/dev/null || { echo "openssl is not installed: skipped"; exit 77; }
tmp="$(mktemp -d)"
pids=()
cleanup() {
  [ -f "$tmp/nginx.pid" ] && kill "$(cat "$tmp/nginx.pid")" 2>/dev/null || true
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
rf_port=$(free_port); plain=$(free_port); tls=$(free_port); redirect=$(free_port)

"$build/server/rayfarmd" --port "$rf_port" --no-access-log >"$tmp/rayfarmd.log" 2>&1 &
pids+=($!)
openssl req -x509 -newkey rsa:2048 -nodes -keyout "$tmp/privkey.pem" -out "$tmp/fullchain.pem" \
  -days 1 -subj /CN=localhost 2>/dev/null
# The shipped files, with only addresses and paths changed (and the second file's zone and
# upstream names, since both load into one nginx here).
sed -e "s/rayfarmd:8080/127.0.0.1:$rf_port/" -e "s/listen 8080/listen $plain/" \
    -e 's/per_address/plain_address/g' -e 's/zone=submits/zone=plain_submits/g' \
    -e 's/upstream rayfarmd/upstream plain_rayfarmd/' \
    -e 's#http://rayfarmd;#http://plain_rayfarmd;#' \
    "$root/docker/nginx.conf" >"$tmp/plain.conf"
sed -e "s#/etc/ssl/rayfarm#$tmp#" -e "s/listen 443 ssl/listen $tls ssl/" \
    -e "s/listen 80;/listen $redirect;/" -e "s/127.0.0.1:8080/127.0.0.1:$rf_port/" \
    "$root/docker/nginx-tls.conf" >"$tmp/tls.conf"
cat >"$tmp/nginx.conf" <<CONF
pid $tmp/nginx.pid;
error_log $tmp/error.log;
events {}
http {
  access_log off;
  client_body_temp_path $tmp/body;
  proxy_temp_path $tmp/proxy;
  include $tmp/plain.conf;
  include $tmp/tls.conf;
}
CONF
nginx -t -q -c "$tmp/nginx.conf" -p "$tmp"
nginx -c "$tmp/nginx.conf" -p "$tmp"
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$rf_port/healthz" >/dev/null && break; sleep 0.1; done

fail() { echo "FAIL: $*"; exit 1; }
scene="$root/scenes/minimal.txt"
"$build/client/rayfarm" render "$scene" --width 40 --height 30 -o "$tmp/local.png" 2>/dev/null
for base in "http://127.0.0.1:$plain" "https://localhost:$tls"; do
  curl -skf --data-binary @"$scene" "$base/render?wait=1&width=40&height=30" -o "$tmp/proxied.png" \
    || fail "render through $base"
  cmp -s "$tmp/local.png" "$tmp/proxied.png" || fail "$base: the image differs from a local render"
  id=$(curl -skf --data-binary @"$scene" "$base/render?width=40&height=30&seed=7" \
       | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')
  # grep reads to the end: with pipefail, grep -q leaving early can fail curl (a closed pipe).
  curl -skfN --max-time 20 "$base/jobs/$id/events" | grep '^event: done' >/dev/null \
    || fail "$base: no 'done' event on the event stream"
done
code=$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$redirect/healthz")
[ "$code" = 301 ] || fail "plain HTTP beside TLS answers $code, not a redirect"

if command -v systemd-analyze >/dev/null; then
  mkdir -p "$tmp/unit"
  # verify checks that ExecStart exists: point it at this build.
  sed -e "s#/usr/local/bin/rayfarmd#$build/server/rayfarmd#" "$root/docker/rayfarmd.service" \
    >"$tmp/unit/rayfarmd.service"
  out=$(systemd-analyze verify "$tmp/unit/rayfarmd.service" 2>&1 || true)
  [ -z "$out" ] || fail "systemd-analyze verify: $out"
fi
echo "deployment files: ok"
