#!/usr/bin/env bash
# e2e: the depth-camera shaft scan's unseen end face. The reconstruction stops short of the
# shaft's bottom with a jagged rim; repair must trim it to one plane and fill it flat, so that
# features finds the `end` plane and its constraints (issues 4 and 5).
set -euo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/scan2cad" reconstruct "$src/fixtures/scans/shaft" -o "$work/mesh.ply" --quiet || fail "reconstruct exited $?"
"$bin/scan2cad" repair "$work/mesh.ply" -o "$work/repaired.ply" --report "$work/repair.json" --quiet || fail "repair exited $?"
"$bin/scan2cad" features "$work/repaired.ply" -o "$work/features.json" --quiet || fail "features exited $?"
"$bin/s2c-bench-features" mesh "$work/repaired.ply" "$src/fixtures/parts/shaft.truth.json" \
  --features "$work/features.json" --json "$work/eval.json" > /dev/null || fail "features evaluation"
python3 - "$work/repair.json" "$work/eval.json" <<'PY'
import json, sys
rep = json.load(open(sys.argv[1]))["counts"]
assert rep["defects_after"]["cad_ready"], rep["defects_after"]["problems"]
holes = [h for r in rep["surface"]["holes"] for h in r["list"]]
caps = [h for h in holes if "end_cap_trim" in h]
assert len(caps) == 1, [h["choice"] for h in holes]
cap = caps[0]
print("end face: Ø %.2f mm, trimmed %.3f mm deep, %s" % (cap["diameter_mm"], cap["end_cap_trim"]["depth_mm"], cap["choice"]))
assert cap["filled"] and cap["method"] == "liepa", cap
assert 15 < cap["diameter_mm"] < 17, cap  # the true end face is Ø 16
assert 0 < cap["end_cap_trim"]["depth_mm"] < 0.02 * cap["diameter_mm"], cap
e = json.load(open(sys.argv[2]))
print("features: primitive recall %.3f (missed %s), constraint P %.3f R %.3f"
      % (e["primitive_recall"], e["missed_primitives"], e["constraint_precision"], e["constraint_recall"]))
assert "end" not in e["missed_primitives"], e  # the end plane within 2° and 0.2 mm of the truth
assert e["primitive_recall"] == 1.0, e
assert e["constraint_recall"] >= 0.9 and e["constraint_precision"] >= 0.9, e
PY
echo "e2e depth_shaft_end_face: ok"
