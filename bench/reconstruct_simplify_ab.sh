#!/usr/bin/env bash
# A/B of the pipeline's stages on each fixture scan: reconstruct with the default (Poisson
# decimated within a tenth of the voxel) against --simplify 0 (Poisson's own mesh, as before stop
# 48), then repair and features on each; wall seconds per stage, two rounds, alternated.
#
#   bench/reconstruct_simplify_ab.sh [BUILD_DIR] [OUT_DIR]     (defaults: build, a new /tmp directory)
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
b="${1:-build}/bin/scan2cad"
out="${2:-$(mktemp -d /tmp/s2c-simplify-ab.XXXXXX)}"
mkdir -p "$out"
[[ -x "$b" && -x /usr/bin/time ]] || { echo "needs $b and /usr/bin/time" >&2; exit 2; }
t() { /usr/bin/time -f "%e" "$@" 2>&1 >/dev/null | tail -1; }
for round in 1 2; do
for s in plate shaft bracket pocket shaft_laser; do
  for v in dec raw; do
    a=""; [ $v = raw ] && a="--simplify 0"
    r=$(t $b reconstruct fixtures/scans/$s -o $out/${s}_$v.ply -q $a)
    p=$(t $b repair $out/${s}_$v.ply -o $out/${s}_${v}_r.ply -q)
    f=$(t $b features $out/${s}_${v}_r.ply -o $out/${s}_${v}_f.json -q)
    echo "$round $s $v reconstruct $r repair $p features $f"
  done
done
done
