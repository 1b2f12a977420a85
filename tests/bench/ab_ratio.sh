#!/usr/bin/env bash
# Two or more rayfarm builds on one scene, taking turns (who goes first rotates each
# round). Each round's render and total times are divided by the first build's in the
# same round, and the medians of those ratios are printed: the machine's drift from
# minute to minute cancels in a pair, which it does not between medians of separate runs.
#
#   tests/bench/ab_ratio.sh SCENE RUNS name=RAYFARM_BINARY ...
#   e.g. tests/bench/ab_ratio.sh /tmp/bench/shallow-60k.txt 11 before=/tmp/old/rayfarm now=build/client/rayfarm
#
# Times are the ones rayfarm reports for itself (`... ms (render ... ms)`), two threads.
set -euo pipefail
[[ $# -ge 3 ]] || { sed -n '2,9p' "$0" >&2; exit 2; }
scene=$1 runs=$2
shift 2
names=() bins=()
for spec in "$@"; do names+=("${spec%%=*}"); bins+=("${spec#*=}"); done
n=${#bins[@]}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for ((i = 0; i < runs; i++)); do
  renders=() totals=()
  for ((j = 0; j < n; j++)); do
    k=$(((i + j) % n))
    line=$("${bins[$k]}" render "$scene" -o "$work/$k.png" --threads 2 2>&1 | grep ' ms (render ')
    totals[k]=$(sed -E 's/.*, ([0-9.]+) ms \(render.*/\1/' <<<"$line")
    renders[k]=$(sed -E 's/.*\(render ([0-9.]+) ms.*/\1/' <<<"$line")
  done
  echo "${renders[*]} ${totals[*]}" >> "$work/times"
done
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
for ((j = 0; j < n; j++)); do
  render=$(awk -v j=$j '{ print $(j + 1) }' "$work/times" | median)
  rr=$(awk -v j=$j '{ print $(j + 1) / $1 }' "$work/times" | median)
  tr=$(awk -v j=$j -v n=$n '{ print $(n + j + 1) / $(n + 1) }' "$work/times" | median)
  printf '%-10s render %8.1f ms   render ratio %.3f   total ratio %.3f\n' "${names[$j]}" "$render" "$rr" "$tr"
done
