#!/usr/bin/env bash
# e2e: `scan2cad run` on a bundled recorded scan, as the README's demo does.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/scan2cad" run "$src/fixtures/scans/plate" --out "$work/out" --quiet || fail "run exited $?"
for f in manifest.json cloud.ply mesh.ply repaired.ply features.json segments.ply check.json \
         reports/reconstruct.json reports/repair.json reports/features.json; do
  [[ -s "$work/out/$f" ]] || fail "missing $f"
done
python3 - "$work/out" <<'PY'
import json, sys, os
out = sys.argv[1]
m = json.load(open(os.path.join(out, "manifest.json")))
st = {s["name"]: s for s in m["stages"]}
assert st["reconstruct"]["status"] == "ok", st["reconstruct"]
assert st["repair"]["status"] == "ok", st["repair"]
assert st["features"]["status"] == "ok", st["features"]
assert st["check"]["status"] == "ok", st["check"]
for s in m["stages"]:
    if s["status"] == "ok":
        assert s["inputs"] and s["outputs"], s
c = json.load(open(os.path.join(out, "check.json")))
for k in ["closed", "boundary_loops", "nonmanifold_edges", "nonmanifold_vertices", "components",
          "self_intersections", "degenerate_faces", "oriented", "cad_ready"]:
    assert k in c, k
r = json.load(open(os.path.join(out, "reports", "reconstruct.json")))
assert r["counts"]["faces"] > 10000, r["counts"]
# The repaired mesh is what the pipeline hands on: it must be CAD-ready.
assert c["cad_ready"], c["problems"]
rep = json.load(open(os.path.join(out, "reports", "repair.json")))["counts"]
assert rep["defects_before"]["boundary_loops"] > 0, "the trimmed scan mesh should have holes to fill"
print("manifest ok:", [(s["name"], s["status"]) for s in m["stages"]])
PY
# Against the true part: the repaired scan is within tolerance of the plate it was scanned from.
"$bin/s2c-bench-accuracy" "$work/out/repaired.ply" "$src/fixtures/parts/plate.stl" > "$work/accuracy.json"
python3 - "$work/accuracy.json" <<'PY'
import json, sys
a = json.load(open(sys.argv[1]))
print("repaired plate: chamfer %.4f mm, coverage %.3f, hausdorff %.3f mm" % (a["chamfer_mm"], a["coverage"], a["hausdorff_mm"]))
assert a["chamfer_mm"] <= 0.03, a["chamfer_mm"]
assert a["coverage"] >= 0.97, a["coverage"]
assert a["hausdorff_mm"] <= 1.0, a["hausdorff_mm"]
PY
# Features of the repaired scan against the plate's ground truth (primitives, lines, constraints).
"$bin/s2c-bench-features" mesh "$work/out/repaired.ply" "$src/fixtures/parts/plate.truth.json" \
  --features "$work/out/features.json" --json "$work/features_eval.json" > /dev/null || fail "features evaluation"
python3 - "$work/out" "$work/features_eval.json" <<'PY'
import json, sys, os
f = json.load(open(os.path.join(sys.argv[1], "features.json")))
assert f["format"] == "scan2cad.features/1", f["format"]
assert f["mesh"]["faces"] > 10000, f["mesh"]
e = json.load(open(sys.argv[2]))
print("features of the repaired plate scan: primitive recall %.3f, line F1 %.3f, constraint recall %.3f"
      % (e["primitive_recall"], e["line_f1"], e["constraint_recall"]))
assert e["primitive_recall"] >= 0.9, e
assert e["line_f1"] >= 0.9, e
assert e["constraint_recall"] >= 0.9, e
PY
# Re-run: everything up to date.
"$bin/scan2cad" run "$src/fixtures/scans/plate" --out "$work/out" --quiet
python3 - "$work/out" <<'PY'
import json, sys, os
m = json.load(open(os.path.join(sys.argv[1], "manifest.json")))
ran = [s["name"] for s in m["stages"] if s["status"] == "ok" and not s.get("skipped")]
assert not ran, f"re-run should skip every stage, ran {ran}"
PY
# Laser scans go through the same pipeline.
"$bin/scan2cad" reconstruct "$src/fixtures/scans/shaft_laser" -o "$work/laser.ply" --quiet || fail "laser reconstruct"
[[ -s "$work/laser.ply" ]] || fail "laser mesh missing"
echo "e2e run_fixture_scan: ok"
