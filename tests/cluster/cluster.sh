#!/usr/bin/env bash
# A farm of three real rayfarmd processes around a private redis-server (unix socket, AOF, in a
# temp dir): (a) a job submitted to node 1 finishes byte-identical to `rayfarm render` while
# node 2 (or 3) is killed with kill -9 holding units; (b) its status and image from every node;
# (c) DELETE on node 3 stops a job running on nodes 1-2 within half a second; (d) Redis frozen:
# 503 from /healthz within seconds; Redis down: 503 with Retry-After on POST /render and
# /healthz, and after a restart from the same AOF the farm works again; (e) a small job sent
# after a big one finishes first; (f) a node frozen past its lease: late results dropped; (g)
# Redis out of memory: 503; (h) small and textured jobs stay on their node, seen from every
# node; (j) a node's own job seen with its progress from the others, and killed rendering it:
# failed on every node, after its restart from its results folder too; (k) a node whose
# password Redis refuses stops at its start, and so does one named as a running node (nodes
# restarted under their own names, in (a), (b) and (j), start). Usage: cluster.sh BUILD_DIR.
# Exit 77 (skipped) without redis-server, unless RAYFARM_REQUIRE_REDIS=1.
set -euo pipefail
# With pipefail, `A | grep -q` fails now and then: grep -q leaves at its first match and A
# dies writing to the closed pipe. Checks here read to the end (grep >/dev/null) or match
# without a pipe.
build=$(cd "$1" && pwd)
src=$(cd "$(dirname "$0")/../.." && pwd)
cd "$src"
if ! command -v redis-server >/dev/null || ! command -v redis-cli >/dev/null; then
  [ "${RAYFARM_REQUIRE_REDIS:-0}" = 1 ] && { echo "redis-server missing and RAYFARM_REQUIRE_REDIS=1"; exit 1; }
  echo "redis-server is not on PATH; skipped"; exit 77
fi
dir=$(mktemp -d /tmp/rfcluster.XXXXXX)
sock=$dir/r.sock
redis_pid=""
pids=(); ports=()
cleanup() {
  for p in "${pids[@]}" $redis_pid; do [ -n "$p" ] && kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [ "${keep:-0}" = 1 ]; then echo "logs in $dir"; else rm -rf "$dir"; fi
}
trap cleanup EXIT
fail() { echo "cluster: FAIL: $*"; keep=1; for i in 1 2 3; do echo "--- node $i"; tail -5 "$dir/node$i.log" 2>/dev/null || true; done; exit 1; }
rcli() { redis-cli -s "$sock" "$@"; }

start_redis() {
  redis-server --port 0 --unixsocket "$sock" --unixsocketperm 700 --dir "$dir" \
    --appendonly yes --appendfsync everysec --save "" --daemonize no >>"$dir/redis.log" 2>&1 &
  redis_pid=$!
  for _ in $(seq 100); do rcli ping 2>/dev/null | grep PONG >/dev/null && return 0; sleep 0.05; done
  fail "redis-server did not start"
}

# start_node N: node N on a free port, one worker, short leases. Ports come from below the
# kernel's ephemeral range (32768-60999), where outgoing connections never land, and a port
# another process holds anyway is retried with a fresh one.
start_node() {
  local n=$1 port attempt lines
  local keep=()  # node 2 keeps its jobs on disk, as a node with --results-dir does
  [ "$n" = 2 ] && keep=(--results-dir "$dir/results2")
  for attempt in 1 2 3 4 5 6 7 8; do
    lines=0; [ -f "$dir/node$n.log" ] && lines=$(wc -l <"$dir/node$n.log")
    port=$((20000 + RANDOM % 12000))
    "$build/server/rayfarmd" --host 127.0.0.1 --port "$port" --no-access-log --workers 1 \
      --redis "unix://$sock" --node-id "node$n" --heartbeat-ms 100 --lease-ms 600 \
      --unit-work 8e6 --distribute-work 1e6 "${keep[@]}" >>"$dir/node$n.log" 2>&1 &
    pids[$n]=$!; ports[$n]=$port
    for _ in $(seq 100); do
      curl -sf -m 2 "http://127.0.0.1:$port/healthz" >/dev/null && return 0
      kill -0 "${pids[$n]}" 2>/dev/null || break
      sleep 0.05
    done
    kill -0 "${pids[$n]}" 2>/dev/null && break  # running but not answering: a real failure
    tail -n +"$((lines + 1))" "$dir/node$n.log" | grep -q "the port is in use" || break
    echo "node $n: port $port taken (attempt $attempt); another" >>"$dir/node$n.log"
  done
  fail "node $n did not start"
}
url() { echo "http://127.0.0.1:${ports[$1]}$2"; }
field() { python3 -c "import json,sys; d=json.load(sys.stdin); print(d$1)"; }
# (grep, not python3, whose start alone takes 0.3 s on a busy machine: states are polled)
state_on() { curl -s "$(url "$1" "/jobs/$2")" | grep -o '"state": *"[a-z]*"' | awk -F'"' 'NR == 1 { print $4 }'; }
metric() { curl -s "$(url "$1" /metrics)" | awk -v m="$2" '$1 == m {print int($2)}'; }

start_redis
# (k) Credentials Redis refuses stop a node at its start, with Redis's words (this Redis has
# no password to give); the nodes that join say so on their first lines.
set +e
refused=$(RAYFARM_REDIS_PASSWORD=x timeout 20 "$build/server/rayfarmd" --host 127.0.0.1 --port 0 \
  --redis "unix://$sock" --node-id refused 2>&1)
code=$?
set -e
[ "$code" = 1 ] || fail "a node with a password this Redis does not have: exit $code: $refused"
[[ $refused == *"refused this node's credentials: ERR AUTH"* ]] || fail "its message: $refused"
for n in 1 2 3; do start_node "$n"; done
for n in 1 2 3; do
  grep -q "farm node node$n at unix://" "$dir/node$n.log" || fail "node $n did not say it joined"
done
# A second node under a running node's name stops at its start too (the restarts below, under
# the names of nodes that were killed, start).
set +e
twin=$(timeout 20 "$build/server/rayfarmd" --host 127.0.0.1 --port 0 --workers 1 \
  --redis "unix://$sock" --node-id node1 --heartbeat-ms 100 --lease-ms 600 2>&1)
code=$?
set -e
[ "$code" = 1 ] || fail "a second node named node1: exit $code: $twin"
[[ $twin == *"--node-id node1: a running node of this farm has that name"* ]] ||
  fail "its message: $twin"
echo "cluster: (k) a password Redis refuses stops a node at start, and so does a second node1;"\
  "the others said they joined"
t0=$SECONDS

# (a) a job of many units on node 1; node 2 (or 3) killed while it holds some.
q="width=320&height=240&spp=200&seed=7"
# (the id read with grep: python3 would take a good part of the job's second to start)
id=$(curl -s --data-binary @scenes/cho.txt "$(url 1 "/render?$q")" | grep -o '"id": *"[0-9a-f]*"' | cut -d'"' -f4)
units=$(rcli hget "rf:job:$id" units)
[ "${units:-0}" -ge 8 ] || fail "expected a job of many units, got '${units:-none}'"
# Node 2 (or 3, whichever a busy machine lets take units first) is frozen (SIGSTOP) at a
# moment Redis says it holds units, then killed: the units it held can only come back through
# the lease.
held=0; victim=""
for _ in $(seq 400); do
  for n in 2 3; do
    if [ "$(rcli xpending rf:work render - + 100 "node$n" | grep -c "^node$n\$" || true)" -gt 0 ]; then
      kill -STOP "${pids[$n]}"
      held=$(rcli xpending rf:work render - + 100 "node$n" | grep -c "^node$n\$" || true)
      [ "$held" -gt 0 ] && { victim=$n; break 2; }
      kill -CONT "${pids[$n]}"
    fi
  done
  sleep 0.01
done
[ "$held" -gt 0 ] || fail "neither node 2 nor node 3 ever held a unit"
kill -9 "${pids[$victim]}"; wait "${pids[$victim]}" 2>/dev/null || true; pids[$victim]=""
echo "cluster: (a) node $victim killed holding $held unit(s) of $units"
for _ in $(seq 300); do
  [ "$(state_on 1 "$id")" = done ] && break
  sleep 0.1
done
[ "$(state_on 1 "$id")" = done ] || fail "the job did not finish: $(curl -s "$(url 1 "/jobs/$id")")"
reclaimed=0
for n in 1 2 3; do
  [ "$n" = "$victim" ] || reclaimed=$((reclaimed + $(metric "$n" rayfarm_units_reclaimed_total)))
done
[ "$reclaimed" -ge 1 ] || fail "no unit was reclaimed"
"$build/client/rayfarm" render scenes/cho.txt --width 320 --height 240 --spp 200 --seed 7 \
  -o "$dir/local.png" -q
curl -s -o "$dir/node1.png" "$(url 1 "/jobs/$id/image")"
cmp "$dir/node1.png" "$dir/local.png" || fail "the farm's image differs from rayfarm render"
echo "cluster: (a) done after the kill, $reclaimed unit(s) reclaimed, byte-identical to rayfarm render ($((SECONDS - t0)) s)"

# (b) every route on every live node (the killed node comes back as a new process first).
start_node "$victim"
for n in 1 2 3; do
  [ "$(state_on "$n" "$id")" = done ] || fail "node $n does not report the job done"
  [ "$(curl -s "$(url "$n" "/jobs/$id")" | field '["progress"]')" = 1.0 ] || fail "node $n: progress"
  curl -s -o "$dir/node$n.png" "$(url "$n" "/jobs/$id/image")"
  cmp "$dir/node$n.png" "$dir/local.png" || fail "node $n serves another image"
  curl -s "$(url "$n" /jobs)" | grep "$id" >/dev/null || fail "node $n: GET /jobs lacks the job"
done
code=$(curl -s -o /dev/null -w '%{http_code}' "$(url 3 /jobs/0123456789abcdef0123456789abcdef)")
[ "$code" = 404 ] || fail "an unknown job gave $code"
# The same request again is answered from the farm's results, on another node.
hit=$(curl -s --data-binary @scenes/cho.txt "$(url 3 "/render?$q&wait=1")" -o "$dir/hit.png" -w '%{http_code}')
[ "$hit" = 200 ] && cmp -s "$dir/hit.png" "$dir/local.png" || fail "the cached answer on node 3 ($hit)"
echo "cluster: (b) status, image and the job list from every node; a repeat answered from the cache"

# (c) DELETE on node 3 of a job rendering on nodes 1 and 2.
long=$(curl -s --data-binary @scenes/cho.txt "$(url 1 "/render?width=640&height=480&spp=256&seed=3")" | field '["id"]')
for _ in $(seq 100); do
  a=$(metric 1 rayfarm_units_in_flight); b=$(metric 2 rayfarm_units_in_flight)
  [ "$a" -ge 1 ] && [ "$b" -ge 1 ] && break
  sleep 0.05
done
[ "$a" -ge 1 ] && [ "$b" -ge 1 ] || fail "the long job did not run on nodes 1 and 2"
# Nothing slow is timed here (python3 alone starts in 0.3 s on a busy machine): the DELETE, then
# Redis asked until it holds no unit unacknowledged.
before=$(date +%s%N)
curl -s -o "$dir/del.json" -w '%{http_code} %{time_total}\n' -X DELETE "$(url 3 "/jobs/$long")" >"$dir/del.code"
stopped=0
while [ $(( ($(date +%s%N) - before) / 1000000 )) -lt 5000 ]; do
  if [ "$(rcli xpending rf:work render | sed -n 1p)" = 0 ]; then stopped=1; break; fi
  sleep 0.01
done
took=$(( ($(date +%s%N) - before) / 1000000 ))
read -r code del_s <"$dir/del.code"
[ "$code" = 200 ] && [ "$(field '["state"]' <"$dir/del.json")" = canceled ] || fail "DELETE on node 3: $code $(cat "$dir/del.json")"
[ "$stopped" = 1 ] && [ "$took" -lt "${CANCEL_MS:-500}" ] || fail "units still held ${CANCEL_MS:-500} ms after the cancel (the DELETE took $del_s s): $(rcli xpending rf:work render | sed -n 1p)"
sleep 0.3
[ "$(metric 1 rayfarm_units_in_flight)" = 0 ] && [ "$(metric 2 rayfarm_units_in_flight)" = 0 ] \
  || fail "a node still renders the canceled job"
echo "cluster: (c) canceled on node 3, every unit stopped within $took ms (the DELETE took $del_s s)"

# (h) A small job stays on the node that took it, and so does one with texture files (only that
# node has them); every node reports it and serves its image.
small=$(curl -s --data-binary @scenes/cho.txt "$(url 3 "/render?width=64&height=48&seed=21")" | field '["id"]')
[ "$(rcli hget "rf:job:$small" local)" = 1 ] && [ "$(rcli hget "rf:job:$small" node)" = node3 ] \
  || fail "the small job is not node 3's own: $(rcli hgetall "rf:job:$small" | head -20 | paste -sd' ')"
for _ in $(seq 200); do [ "$(state_on 1 "$small")" = done ] && break; sleep 0.05; done
[ "$(state_on 1 "$small")" = done ] || fail "node 1 does not see node 3's small job done"
curl -s -o "$dir/small.png" "$(url 1 "/jobs/$small/image")"
"$build/client/rayfarm" render scenes/cho.txt --width 64 --height 48 --seed 21 -o "$dir/small-local.png" -q
cmp -s "$dir/small.png" "$dir/small-local.png" || fail "node 1 serves another image of node 3's job"
(cd scenes && curl -s -o "$dir/tex.png" -w '%{http_code}' -F scene=@textures.txt \
  -F 'textures/bricks.ppm=@textures/bricks.ppm' -F 'textures/checker.ppm=@textures/checker.ppm' \
  -F 'textures/slide.ppm=@textures/slide.ppm' "$(url 2 "/render?width=160&height=120&wait=1")") \
  >"$dir/tex.code"
[ "$(cat "$dir/tex.code")" = 200 ] || fail "a scene with textures on a farm node gave $(cat "$dir/tex.code")"
(cd scenes && "$build/client/rayfarm" render textures.txt --width 160 --height 120 -o "$dir/tex-local.png" -q)
cmp -s "$dir/tex.png" "$dir/tex-local.png" || fail "the textured render differs from rayfarm render"
echo "cluster: (h) a small job and a textured one rendered on their own nodes, seen from every node"

# (i) An Idempotency-Key is the farm's: the same request on another node is the same job; the
# key with another request is 422 on any node. A job's warnings are seen from every node.
k="key-$RANDOM"
(cat scenes/minimal.txt; printf 'sphere\n{  material grey\n   center 4 3 20\n   radius 1\n}\n') >"$dir/warn.txt"
first=$(curl -s -H "Idempotency-Key: $k" --data-binary @"$dir/warn.txt" "$(url 1 "/render?width=160&height=120&spp=8")" | field '["id"]')
again=$(curl -s -D "$dir/again.h" -H "Idempotency-Key: $k" --data-binary @"$dir/warn.txt" "$(url 2 "/render?width=160&height=120&spp=8")" | field '["id"]')
[ "$first" = "$again" ] && grep -qi '^Idempotent-Replayed: true' "$dir/again.h" \
  || fail "the same key on node 2 gave job $again, not $first"
code=$(curl -s -o "$dir/reused.json" -w '%{http_code}' -H "Idempotency-Key: $k" --data-binary @"$dir/warn.txt" "$(url 3 "/render?width=160&height=120&spp=9")")
[ "$code" = 422 ] && grep -q idempotency_key_reused "$dir/reused.json" || fail "the key reused on node 3 gave $code $(cat "$dir/reused.json")"
for n in 1 3; do
  curl -s "$(url "$n" "/jobs/$first")" | grep '"warnings": *\[ *{' >/dev/null || fail "node $n does not show the job's warnings"
done
echo "cluster: (i) an Idempotency-Key and a job's warnings hold on every node"

# (e) Fairness across nodes: a small job sent after a big one finishes first.
big=$(curl -s --data-binary @scenes/cho.txt "$(url 1 "/render?width=640&height=480&spp=128&seed=11")" | field '["id"]')
sleep 0.2
# (above --distribute-work, so the farm feeds it: one unit)
small=$(curl -s --data-binary @scenes/cho.txt "$(url 3 "/render?width=160&height=120&spp=8&seed=12")" | field '["id"]')
[ "$(rcli hget "rf:job:$small" units)" = 1 ] || fail "the small job is not one unit of the farm's"
for _ in $(seq 300); do
  [ "$(state_on 2 "$small")" = done ] && break
  sleep 0.05
done
[ "$(state_on 2 "$small")" = done ] || fail "the small job did not finish"
[ "$(state_on 2 "$big")" != done ] || fail "the small job waited for the big one"
echo "cluster: (e) a small job sent after a big one finished first ($(rcli hget "rf:job:$big" done)/$(rcli hget "rf:job:$big" units) units of the big one done)"

# (f) A node frozen (SIGSTOP) past its lease: its units are rendered elsewhere; when it wakes,
# its late results are dropped and the image stays the same bytes.
for _ in $(seq 400); do
  [ "$(rcli xpending rf:work render - + 100 node1 | grep -c '^node1$' || true)" -gt 0 ] && break
  sleep 0.01
done
kill -STOP "${pids[1]}"
for _ in $(seq 600); do
  [ "$(state_on 3 "$big")" = done ] && break
  sleep 0.1
done
[ "$(state_on 3 "$big")" = done ] || { kill -CONT "${pids[1]}"; fail "the big job did not finish without node 1"; }
curl -s -o "$dir/big-before.png" "$(url 3 "/jobs/$big/image")"
kill -CONT "${pids[1]}"
sleep 1.5  # node 1 finishes its unit, is told the job is over, and goes on
curl -s -o "$dir/big-after.png" "$(url 1 "/jobs/$big/image")"
cmp -s "$dir/big-before.png" "$dir/big-after.png" || fail "a late result changed the image"
"$build/client/rayfarm" render scenes/cho.txt --width 640 --height 480 --spp 128 --seed 11 \
  -o "$dir/big-local.png" -q
cmp -s "$dir/big-after.png" "$dir/big-local.png" || fail "the big job differs from rayfarm render"
[ "$(curl -s -o /dev/null -w '%{http_code}' "$(url 1 /healthz)")" = 200 ] || fail "node 1 after SIGCONT"
echo "cluster: (f) node 1 frozen past its lease: the job finished elsewhere, its late result was dropped"

# (g) Redis out of memory: submissions get 503 + Retry-After, reads still answer, no crash.
rcli config set maxmemory 1 >/dev/null
headers=$(curl -s -D - -o "$dir/oom.json" --data-binary @scenes/cho.txt "$(url 2 "/render?width=64&height=48&seed=13")")
[[ ${headers%%$'\n'*} == *" 503"* ]] || fail "POST /render with Redis out of memory: ${headers%%$'\n'*} $(cat "$dir/oom.json")"
grep -qi '^Retry-After:' <<<"$headers" || fail "the out-of-memory 503 has no Retry-After"
[ "$(state_on 2 "$big")" = done ] || fail "GET /jobs/ID with Redis out of memory"
rcli config set maxmemory 0 >/dev/null
code=$(curl -s -o /dev/null -w '%{http_code}' --data-binary @scenes/cho.txt "$(url 2 "/render?width=64&height=48&seed=13&wait=1")")
[ "$code" = 200 ] || fail "a render once Redis had memory again gave $code"
for n in 1 2 3; do kill -0 "${pids[$n]}" || fail "node $n died"; done
echo "cluster: (g) Redis out of memory: 503 + Retry-After, reads answered, then renders again"

# (j) A node killed while rendering its own job (textures keep it there): the job fails with
# node_lost on every node, instead of running forever.
tex=$(cd scenes && curl -s -F scene=@textures.txt -F 'textures/bricks.ppm=@textures/bricks.ppm' \
  -F 'textures/checker.ppm=@textures/checker.ppm' -F 'textures/slide.ppm=@textures/slide.ppm' \
  "$(url 2 "/render?width=1280&height=960&spp=64")" | field '["id"]')
for _ in $(seq 100); do [ "$(state_on 2 "$tex")" = running ] && break; sleep 0.05; done
# Its progress, which node 2 writes with its heartbeats, is seen from the other nodes.
progress_on() { curl -s "$(url "$1" "/jobs/$2")" | grep -o '"progress": *[0-9.e-]*' | sed 's/.*: *//'; }
for _ in $(seq 100); do
  awk -v p="$(progress_on 1 "$tex")" 'BEGIN { exit !(p > 0) }' && break
  sleep 0.05
done
awk -v p="$(progress_on 1 "$tex")" 'BEGIN { exit !(p > 0 && p < 1) }' \
  || fail "node 1 sees node 2's own running job at progress $(progress_on 1 "$tex") (node 2: $(progress_on 2 "$tex"))"
echo "cluster: (j) node 2's own job seen at progress $(progress_on 1 "$tex") from node 1"
kill -9 "${pids[2]}"; wait "${pids[2]}" 2>/dev/null || true; pids[2]=""
for _ in $(seq 100); do [ "$(state_on 1 "$tex")" = failed ] && break; sleep 0.1; done
curl -s "$(url 1 "/jobs/$tex")" | grep '"code": *"node_lost"' >/dev/null \
  || fail "node 2's own job after its death: $(curl -s "$(url 1 "/jobs/$tex")" | head -c 400)"
# Node 2 comes back with its results folder, which still holds the job unfinished: the farm's
# answer stands on every node, node 2 included (it does not render the job again).
start_node 2
sleep 1
for n in 1 2 3; do
  [ "$(state_on "$n" "$tex")" = failed ] || fail "after node 2's restart, node $n says the job is $(state_on "$n" "$tex")"
done
echo "cluster: (j) a node killed rendering its own job: the job failed with node_lost, on every node after its restart too"

# (d) Redis frozen (stopped, not refusing): a health check is answered 503 in a few seconds,
# not after the workers' 20 s timeout. Then Redis down, and back from its AOF.
kill -STOP "$redis_pid"
t1=$EPOCHREALTIME
code=$(curl -s -m 15 -o /dev/null -w '%{http_code}' "$(url 3 /healthz)")
took=$(awk -v a="$t1" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
kill -CONT "$redis_pid"
[ "$code" = 503 ] || fail "/healthz with Redis frozen gave $code after $took s"
awk -v t="$took" 'BEGIN { exit !(t < 6) }' || fail "/healthz with Redis frozen took $took s"
echo "cluster: (d) Redis frozen: /healthz said 503 in $took s"
for _ in $(seq 100); do
  [ "$(curl -s -o /dev/null -w '%{http_code}' "$(url 3 /healthz)")" = 200 ] && break
  sleep 0.1
done
kill -9 "$redis_pid"; wait "$redis_pid" 2>/dev/null || true; redis_pid=""
headers=$(curl -s -D - -o /dev/null --data-binary @scenes/cho.txt "$(url 1 "/render?width=64&height=48")")
[[ ${headers%%$'\n'*} == *" 503"* ]] || fail "POST /render without Redis: ${headers%%$'\n'*}"
grep -qi '^Retry-After:' <<<"$headers" || fail "503 without Retry-After"
code=$(curl -s -o /dev/null -w '%{http_code}' "$(url 2 /healthz)")
[ "$code" = 503 ] || fail "/healthz without Redis gave $code"
code=$(curl -s -o /dev/null -w '%{http_code}' "$(url 3 "/jobs/$id")")
[ "$code" = 503 ] || fail "GET /jobs/ID without Redis gave $code"
start_redis
# Every node back (each retries with its own backoff, up to 5 s, longer after the freeze's
# failed attempts than after one outage), then the job is read from the last of them.
for n in 1 2 3; do
  for _ in $(seq 150); do
    [ "$(curl -s -o /dev/null -w '%{http_code}' "$(url "$n" /healthz)")" = 200 ] && break
    sleep 0.1
  done
  [ "$(curl -s -o /dev/null -w '%{http_code}' "$(url "$n" /healthz)")" = 200 ] || fail "node $n did not recover"
done
[ "$(state_on 3 "$id")" = done ] || fail "the job from (a) was lost with the restart: $(curl -s "$(url 3 "/jobs/$id")" | head -c 300)"
new=$(curl -s --data-binary @scenes/cho.txt "$(url 2 "/render?width=96&height=64&spp=4&seed=5&wait=1")" -o "$dir/after.png" -w '%{http_code}')
[ "$new" = 200 ] || fail "a render after the restart gave $new"
for n in 1 2 3; do kill -0 "${pids[$n]}" || fail "node $n died"; done
echo "cluster: (d) 503 + Retry-After while Redis was down; after its restart the farm renders again"
echo "cluster: ok ($((SECONDS - t0)) s)"
