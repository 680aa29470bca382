#!/bin/bash
# Runs one scan2cad-features binary on meshes of the fixture parts and scores each against its
# part's ground truth (s2c-bench-features mesh): one row per mesh with primitive recall, type
# accuracy, line P / R / F1, circle radius error, constraint precision and recall. The part is the
# first fixture part name (plate, shaft, bracket, pocket) in the mesh's path. Two binaries' rows
# diffed show what a change does to quality (bench/README.md, features).
#   bench/features_truth.sh BINARY MESH...
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 SCAN2CAD_FEATURES_BINARY MESH..." >&2
  exit 2
fi
bin=$1
shift
here=$(cd "$(dirname "$0")/.." && pwd)
bench=$here/build/bin/s2c-bench-features
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "| mesh | primitive recall | type accuracy | line P | line R | line F1 | circle radius err mean / max | constraint P | constraint R |"
echo "|---|---|---|---|---|---|---|---|---|"
for mesh in "$@"; do
  part=$(grep -oE 'plate|shaft|bracket|pocket' <<<"$mesh" | head -1)
  if [ -z "$part" ]; then
    echo "| $mesh | no fixture part named in the path |"
    continue
  fi
  if ! "$bin" "$mesh" -o "$work/f.json" -q 2>/dev/null; then
    echo "| $mesh | features failed |"
    continue
  fi
  row=$("$bench" mesh "$mesh" "$here/fixtures/parts/$part.truth.json" --features "$work/f.json" 2>&1 |
    grep "^| $part" | cut -d"|" -f6-13)
  echo "| $mesh |$row|"
done
