#!/usr/bin/env bash
# The course conformance table: every scene of manifest.txt rendered with --profile cpsc102
# (whole processes, 2 threads) and compared with its reference image, channel by channel.
#   tests/conformance/run.sh [BUILD_DIR] [COURSE_DIR]
# COURSE_DIR defaults to tests/conformance/course; any folder in the course's layout with
# scene.txt + scene.png pairs (or .ppm) works, e.g. a fuller copy of the course's files.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../../build}
course=${2:-$here/course}
rayfarm=$build/client/rayfarm
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| scene | exact channels | differing pixels | max diff | render time |"
echo "|---|---:|---:|---:|---:|"
find "$course" -name '*.txt' | sort | while read -r scene; do
  ref=""
  for ext in png ppm; do [ -s "${scene%.txt}.$ext" ] && ref="${scene%.txt}.$ext" && break; done
  [ -n "$ref" ] || continue
  rel=${scene#$course/}
  opts=$(awk -v s="$rel" '$1 == s && $2 != "-" { print "--" $2 }' "$here/manifest.txt" | sed 's/=/ /')
  case "$rel" in */aa/*) opts=${opts:-"--spp 16"};; esac
  start=$(date +%s%N)
  if ! $rayfarm render "$scene" --profile cpsc102 $opts --threads 2 -o "$tmp/out.png" 2>"$tmp/err"; then
    echo "| $rel | failed: $(head -c 120 "$tmp/err" | tr '\n' ' ') | | | |"
    continue
  fi
  ms=$(( ($(date +%s%N) - start) / 1000000 ))
  cmp=$($rayfarm compare "$tmp/out.png" "$ref" || true)
  channels=$(echo "$cmp" | awk '/differing_channels/ { print $2, $4 }')
  pixels=$(echo "$cmp" | awk '/differing_pixels/ { print $2 }')
  max=$(echo "$cmp" | awk '/max_abs/ { print $2 }')
  exact=$(echo "$channels" | awk '{ printf "%.3f%%", 100 * (1 - $1 / $2) }')
  echo "| $rel | $exact | $pixels | $max | $ms ms |"
done
