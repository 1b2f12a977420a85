#!/usr/bin/env bash
# What a run pays for following other work: whole-process wall times of one scene, back to
# back, and each run after two seconds of both cores spinning (touching no memory) or of
# sleep. On the virtual machines measured, any such pause makes the next run's fresh memory
# cost 1-2 ms per MB (the host supplies it again), which is what a run right after POV-Ray
# pays in tests/bench/vs_povray.sh (docs/performance.md, twenty-second round).
#
#   tests/bench/after_pause.sh SCENE RUNS name=RAYFARM_BINARY ...
#   e.g. tests/bench/after_pause.sh /tmp/bench/shallow-60k.txt 9 now=build/client/rayfarm
#
# With several builds, they take turns in every condition (who goes first rotates), each
# run after its own pause. Medians, and each build's median ratio to the first in the
# same round. Two threads; bash 5 (its EPOCHREALTIME clock).
set -euo pipefail
[[ $# -ge 3 ]] || { sed -n '2,12p' "$0" >&2; exit 2; }
[[ -n ${EPOCHREALTIME:-} ]] || { echo "needs bash 5 (its EPOCHREALTIME clock)" >&2; exit 2; }
scene=$1 runs=$2
shift 2
names=() bins=()
for spec in "$@"; do names+=("${spec%%=*}"); bins+=("${spec#*=}"); done
n=${#bins[@]}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Both cores busy for two seconds, no memory touched.
spin() {
  local end=$((${EPOCHREALTIME/[.,]/} + 2000000))
  for _ in 1 2; do
    (while ((${EPOCHREALTIME/[.,]/} < end)); do :; done) &
  done
  wait
}

# Wall milliseconds of one render, on the shell's own clock.
wall() {
  local t0=$EPOCHREALTIME t1
  "$1" render "$scene" -o "$work/out.png" --threads 2 -q || { echo "failed: $1" >&2; exit 1; }
  t1=$EPOCHREALTIME
  awk -v a="${t0/,/.}" -v b="${t1/,/.}" 'BEGIN { printf "%.1f", (b - a) * 1000 }'
}

median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

for condition in back-to-back spin sleep; do
  : > "$work/times"
  for ((i = 0; i < runs; i++)); do
    row=()
    for ((j = 0; j < n; j++)); do
      k=$(((i + j) % n))
      case $condition in
        back-to-back) "${bins[$k]}" render "$scene" -o "$work/out.png" --threads 2 -q ;;
        spin) spin ;;
        sleep) sleep 2 ;;
      esac
      row[k]=$(wall "${bins[$k]}")
    done
    echo "${row[*]}" >> "$work/times"
  done
  for ((j = 0; j < n; j++)); do
    m=$(awk -v j=$j '{ print $(j + 1) }' "$work/times" | median)
    r=$(awk -v j=$j '{ print $(j + 1) / $1 }' "$work/times" | median)
    printf '%-13s %-10s %8.1f ms   ratio to %s %.3f\n' "$condition" "${names[$j]}" "$m" "${names[0]}" "$r"
  done
done
