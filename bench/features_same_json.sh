#!/bin/bash
# Do two scan2cad-features binaries give the same features.json (equal as JSON) on the real CAD
# meshes, the defective corpus, the fixture parts and any further meshes named? A speed change
# that should not change results is checked with this (bench/README.md, features speed).
#   bench/features_same_json.sh OLD NEW [MESH...]
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 OLD_BINARY NEW_BINARY [MESH...]" >&2
  exit 2
fi
old=$1 new=$2
shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
real=$here/../shared/data/real
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
n=0 differ=0
for mesh in "$real"/cad/*.off "$real"/cad/*.stl "$real"/defective/*.{off,obj,ply,stl,vtk} "$here"/fixtures/parts/*.stl "$@"; do
  [ -e "$mesh" ] || continue
  rm -f "$work/old.json" "$work/new.json"
  "$old" "$mesh" -o "$work/old.json" -q 2>/dev/null; r_old=$?
  "$new" "$mesh" -o "$work/new.json" -q 2>/dev/null; r_new=$?
  n=$((n + 1))
  same=1
  if [ "$r_old" != "$r_new" ]; then
    same=0
  elif [ "$r_old" = 0 ]; then
    python3 -c "import json, sys; sys.exit(json.load(open(sys.argv[1])) != json.load(open(sys.argv[2])))" \
      "$work/old.json" "$work/new.json" || same=0
  fi
  if [ $same = 1 ]; then echo "same  $mesh (exit $r_old)"; else echo "DIFF  $mesh (exit $r_old / $r_new)"; differ=$((differ + 1)); fi
done
echo "$n meshes, $differ differ"
[ $differ = 0 ]
