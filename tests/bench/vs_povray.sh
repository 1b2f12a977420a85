#!/usr/bin/env bash
# Whole-process wall time of rayfarm against POV-Ray 3.7 at 800x600, 1 sample per pixel,
# two threads, on the benchmark set: the lecture scene, the 8,000-sphere grid, 100,000 random
# spheres, the course lab with the newer kinds, and the scenes of tests/bench/gen-bench-scenes.py.
# Each scene is exported with `rayfarm convert --to pov`, then the two renderers run
# alternately (so both see the same machine load); medians and their ratio are printed, with
# the load average before and after.
#
#   tests/bench/vs_povray.sh [BUILD_DIR] [RUNS] [SCENE...]   (from the repository root;
#                                                             defaults: build 5, every scene)
#   BEFORE=OTHER_BUILD_DIR tests/bench/vs_povray.sh ...      also runs that build's rayfarm in
#                                                             the same rotation (before/after)
#   RUNS_SHOWN=1 tests/bench/vs_povray.sh ...                 also prints every run's seconds and
#                                                             the range of the runs' own ratios
#                                                             (run i of each renderer paired)
set -euo pipefail
[[ -n ${EPOCHREALTIME:-} ]] || { echo "needs bash 5 (its EPOCHREALTIME clock)" >&2; exit 2; }

build=${1:-build}
runs=${2:-5}
shift $(( $# < 2 ? $# : 2 ))
rayfarm="$build/client/rayfarm"
[[ -x "$rayfarm" ]] || { echo "no $rayfarm: build first (cmake --build $build)" >&2; exit 2; }
before=${BEFORE:+$BEFORE/client/rayfarm}
[[ -z "$before" || -x "$before" ]] || { echo "no $before" >&2; exit 2; }
command -v povray >/dev/null || { echo "povray is not installed" >&2; exit 2; }

generated=$(python3 tests/bench/gen-bench-scenes.py --list | awk '{ print $1 }')
scenes=("$@")
[[ ${#scenes[@]} -gt 0 ]] || scenes=(cho grid-8000 random-100k lab $generated)

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

for scene in "${scenes[@]}"; do
  case $scene in
    cho | grid-8000 | lab) cp "scenes/$scene.txt" "$work/$scene.txt" ;;
    random-100k) python3 scenes/gen-random-spheres.py > "$work/random-100k.txt" ;;
    *) python3 tests/bench/gen-bench-scenes.py "$work" "$scene" ;;
  esac
done

# Runs "$@" once with output discarded; prints its wall time in seconds, from just before the
# shell starts it to just after it has exited, on the shell's own clock (bash 5). Read by
# running `date`, the clock counted that process's start-up in every run: 6 ms on the
# machines measured, 5% of a 0.12 s run and nothing of POV-Ray's seconds. No subshell
# either: `$(...)` forks one. (Some locales write the clock with a decimal comma.)
wall() {
  local t0=$EPOCHREALTIME t1
  "$@" >/dev/null 2>&1 || { echo "failed: $*" >&2; exit 1; }
  t1=$EPOCHREALTIME
  awk -v a="${t0/,/.}" -v b="${t1/,/.}" 'BEGIN { printf "%.4f\n", b - a }'
}

median() { sort -g | awk '{ v[NR] = $1 } END { m = int((NR + 1) / 2); print (NR % 2) ? v[m] : (v[m] + v[m + 1]) / 2 }'; }

echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
if [[ -n "$before" ]]; then
  printf '%-18s %10s %10s %10s %8s %8s\n' scene before_s rayfarm_s povray_s before ratio
else
  printf '%-18s %10s %10s %8s\n' scene rayfarm_s povray_s ratio
fi
for scene in "${scenes[@]}"; do
  model="$work/$scene.txt"
  "$rayfarm" convert "$model" --to pov -o "$work/$scene.pov"
  : > "$work/$scene.rf"
  : > "$work/$scene.before"
  : > "$work/$scene.pov.t"
  for ((i = 0; i < runs; i++)); do
    # The run right after POV-Ray pays for the memory it freed (on the virtual machines
    # measured, 10-40% on the larger scenes; the next run finds it warm): with a second build,
    # the two take turns going first.
    if [[ -n "$before" && $((i % 2)) -eq 0 ]]; then
      wall "$before" render "$model" --threads 2 -o "$work/$scene.png" >> "$work/$scene.before"
      wall "$rayfarm" render "$model" --threads 2 -o "$work/$scene.png" >> "$work/$scene.rf"
    elif [[ -n "$before" ]]; then
      wall "$rayfarm" render "$model" --threads 2 -o "$work/$scene.png" >> "$work/$scene.rf"
      wall "$before" render "$model" --threads 2 -o "$work/$scene.png" >> "$work/$scene.before"
    else
      wall "$rayfarm" render "$model" --threads 2 -o "$work/$scene.png" >> "$work/$scene.rf"
    fi
    wall povray "+I$work/$scene.pov" +W800 +H600 -A +WT2 "+O$work/$scene-pov.png" -D \
      >> "$work/$scene.pov.t"
  done
  if [[ -n "${RUNS_SHOWN:-}" ]]; then
    [[ -z "$before" ]] || echo "  before runs:  $(tr '\n' ' ' < "$work/$scene.before")"
    echo "  rayfarm runs: $(tr '\n' ' ' < "$work/$scene.rf")"
    echo "  povray runs:  $(tr '\n' ' ' < "$work/$scene.pov.t")"
    paste "$work/$scene.rf" "$work/$scene.pov.t" |
      awk '{ r = $2 / $1; lo = NR == 1 || r < lo ? r : lo; hi = NR == 1 || r > hi ? r : hi }
           END { printf "  ratios of paired runs: %.1fx to %.1fx\n", lo, hi }'
  fi
  rf=$(median < "$work/$scene.rf")
  pv=$(median < "$work/$scene.pov.t")
  ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1fx", b / a }'; }
  if [[ -n "$before" ]]; then
    bf=$(median < "$work/$scene.before")
    printf '%-18s %10.3f %10.3f %10.3f %8s %8s\n' "$scene" "$bf" "$rf" "$pv" "$(ratio "$bf" "$pv")" \
      "$(ratio "$rf" "$pv")"
  else
    printf '%-18s %10.3f %10.3f %8s\n' "$scene" "$rf" "$pv" "$(ratio "$rf" "$pv")"
  fi
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
