#!/usr/bin/env bash
# e2e (issue 4): every mesh in ../shared/data/real/defective/ comes out of `scan2cad repair`
# CAD-ready (as judged by `scan2cad check` on the written file, self-intersections included), and
# the CAD meshes in cad/ pass through untouched, sharp edges and all. Skips (77) without the data.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
real="$src/../shared/data/real"
[[ -d "$real" ]] || { echo "no $real: skipped"; exit 77; }
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

for f in "$real"/defective/*.{off,obj,ply,stl,vtk}; do
  [[ -e "$f" ]] || continue
  name=$(basename "$f"); out="$work/${name%.*}.ply"
  before=$(sha256sum "$f")
  "$bin/scan2cad" repair "$f" -o "$out" --report "$work/${name%.*}.json" --quiet || fail "repair $name exited $?"
  [[ "$(sha256sum "$f")" == "$before" ]] || fail "$name was modified"
  "$bin/scan2cad" check "$out" > "$work/${name%.*}.check.json"
  python3 - "$work/${name%.*}.check.json" "$work/${name%.*}.json" "$name" <<'PY'
import json, sys
c = json.load(open(sys.argv[1])); r = json.load(open(sys.argv[2]))["counts"]
assert c["cad_ready"], (sys.argv[3], c["problems"])
b = r["defects_before"]
print("%-32s %-10s faces %6d -> %6d  loops %3d -> 0  nmE %3d  SI %3d -> 0" % (
    sys.argv[3], r["path"], b["faces"], c["faces"], b["boundary_loops"], b["nonmanifold_edges"], b["self_intersections"]))
PY
done

for f in "$real"/cad/*.{off,stl}; do
  [[ -e "$f" ]] || continue
  name=$(basename "$f"); out="$work/cad_${name%.*}.ply"
  "$bin/scan2cad" check "$f" > "$work/cad_${name%.*}.before.json"
  ready=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["cad_ready"])' "$work/cad_${name%.*}.before.json")
  "$bin/scan2cad" repair "$f" -o "$out" --report "$work/cad_${name%.*}.json" --quiet || fail "repair $name exited $?"
  "$bin/scan2cad" check "$out" > "$work/cad_${name%.*}.after.json"
  python3 - "$work/cad_${name%.*}.json" "$work/cad_${name%.*}.after.json" "$name" "$ready" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["counts"]; c = json.load(open(sys.argv[2]))
assert c["cad_ready"], (sys.argv[3], c["problems"])
if sys.argv[4] == "True":  # CAD-ready input passes through untouched (sharp edges and all)
    assert r["path"] == "unchanged", (sys.argv[3], r["path"])
else:                      # cgal_blade is open: surface repair keeps every input triangle
    assert r["path"] == "surface", (sys.argv[3], r["path"])
    assert c["faces"] >= r["defects_before"]["faces"], (c["faces"], r["defects_before"]["faces"])
print("%-32s %s" % (sys.argv[3], r["path"]))
PY
done
echo "e2e repair_real: ok"
