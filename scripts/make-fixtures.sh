#!/usr/bin/env bash
# Regenerates the fixture parts in fixtures/parts/: exports every NAME.scad to NAME.stl with
# OpenSCAD (ASCII STL, triangles in canonical order so re-exports are byte-identical), rewrites
# NAME.truth.json from make_truth.py, then runs verify_truth.py (exit status non-zero if any
# mesh or truth file fails its checks).
#   scripts/make-fixtures.sh            all parts
#   scripts/make-fixtures.sh plate ...  only the named parts (verification still covers all)
# Installs the Debian package openscad if it is missing (non-interactive; sudo when not root).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
parts="$here/../fixtures/parts"
cd "$parts"

if ! command -v openscad >/dev/null 2>&1; then
  sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  echo "make-fixtures: installing openscad"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends openscad
fi
if ! command -v python3 >/dev/null 2>&1; then
  echo "make-fixtures: python3 is required" >&2
  exit 2
fi

if (($# > 0)); then
  names=("$@")
else
  names=()
  for f in *.scad; do names+=("${f%.scad}"); done
fi

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
for name in "${names[@]}"; do
  if [[ ! -f "$name.scad" ]]; then
    echo "make-fixtures: no such part: $parts/$name.scad" >&2
    exit 2
  fi
  # export to a temporary file, then rename: a failed export never leaves a partial mesh
  if ! openscad --export-format asciistl -o "$name.stl.tmp" "$name.scad" >"$log" 2>&1; then
    cat "$log" >&2
    rm -f "$name.stl.tmp"
    echo "make-fixtures: openscad failed on $name.scad" >&2
    exit 3
  fi
  if grep -qi "warning\|error" "$log"; then
    grep -i "warning\|error" "$log" >&2
  fi
  # OpenSCAD 2021 writes CGAL results in a run-dependent triangle order: canonicalize so a
  # re-export of unchanged geometry is byte-identical
  python3 canonical_stl.py "$name.stl.tmp"
  mv -f "$name.stl.tmp" "$name.stl"
  echo "make-fixtures: $name.scad -> $name.stl ($(grep -c 'facet normal' "$name.stl") triangles)"
done

python3 make_truth.py
python3 verify_truth.py
