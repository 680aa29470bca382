#!/usr/bin/env bash
# e2e: `scan2cad run` on a bundled recorded scan, as the README's demo does.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

# The bundled scan is replayed through the acquire stage (as a live capture would be recorded),
# then every stage runs on the recording.
ref="$src/fixtures/parts/plate.stl"
"$bin/scan2cad" run --from "replay:$src/fixtures/scans/plate" --out "$work/out" --reference "$ref" --quiet || fail "run exited $?"
[[ $(grep -vc '^#' "$work/out/stream/depth.txt") == $(grep -vc '^#' "$src/fixtures/scans/plate/depth.txt") ]] \
  || fail "the recorded stream does not hold every frame of the replay"
for f in manifest.json cloud.ply mesh.ply repaired.ply features.json segments.ply check.json report.html \
         reports/acquire.json reports/reconstruct.json reports/repair.json reports/features.json reports/report.json; do
  [[ -s "$work/out/$f" ]] || fail "missing $f"
done
python3 - "$work/out" <<'PY'
import json, sys, os
out = sys.argv[1]
m = json.load(open(os.path.join(out, "manifest.json")))
st = {s["name"]: s for s in m["stages"]}
assert st["acquire"]["status"] == "ok", st["acquire"]
assert st["reconstruct"]["status"] == "ok", st["reconstruct"]
assert st["repair"]["status"] == "ok", st["repair"]
assert st["features"]["status"] == "ok", st["features"]
assert st["check"]["status"] == "ok", st["check"]
assert st["report"]["status"] == "ok", st["report"]
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
# report.html: a picture per stage (2 views each) and the deviation map against the true part,
# whose numbers agree with the independent accuracy check above.
python3 - "$work/out" "$work/accuracy.json" <<'PY'
import json, os, re, sys
out = sys.argv[1]
page = open(os.path.join(out, "report.html"), encoding="utf-8").read()
images = re.findall(r'<img src="([^"]+)"', page)
for stem in ["cloud", "mesh", "repaired", "features", "deviation"]:
    assert any(("/%s_iso.png" % stem) in i for i in images), (stem, images)
assert any("/repaired_closeup.png" in i for i in images), "the holes the repair filled get a close-up"
for i in images:
    data = open(os.path.join(out, i), "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000, i
for heading in ["Stages", "Defects found and fixed", "CAD-ready check", "Features", "Deviation from plate.stl"]:
    assert heading in page, heading
assert "<svg" in page, "legend and histogram are inline SVG"
dev = json.load(open(os.path.join(out, "reports", "report.json")))["counts"]["deviation"]
acc = json.load(open(sys.argv[2]))
print("report deviation: rms %.4f mm, mean %+.4f mm, max |d| %.3f mm, range ±%g mm (chamfer %.4f)"
      % (dev["rms_mm"], dev["mean_mm"], dev["max_abs_mm"], dev["range_mm"], acc["chamfer_mm"]))
assert dev["mean_abs_mm"] <= acc["chamfer_mm"] * 1.5 + 0.005, (dev, acc["chamfer_mm"])
assert dev["rms_mm"] <= 0.05 and abs(dev["mean_mm"]) <= 0.02, dev
assert dev["max_abs_mm"] <= acc["hausdorff_mm"] + 0.01, (dev, acc["hausdorff_mm"])
rep = json.load(open(os.path.join(out, "reports", "report.json")))["counts"]
assert rep["filled_faces"] > 0, "the trimmed scan mesh has holes: the repair adds surface, shown in orange"
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
print("features of the repaired plate scan: primitive recall %.3f, line F1 %.3f, constraint P %.3f R %.3f, "
      "circle radius error max %.2f %%" % (e["primitive_recall"], e["line_f1"], e["constraint_precision"],
                                          e["constraint_recall"], 100 * e["circle_radius_err_max"]))
assert e["primitive_recall"] >= 0.9, e
assert e["line_f1"] >= 0.9, e
assert e["constraint_recall"] >= 0.9, e
assert e["constraint_precision"] >= 0.98, e
# The hole rims are the plane ∩ cylinder circles, not the crest of the scan's rounded crease
# (which is 2.5 % wider).
assert e["circle_radius_err_max"] <= 0.01, e
PY
# Re-run: everything up to date.
"$bin/scan2cad" run --from "replay:$src/fixtures/scans/plate" --out "$work/out" --reference "$ref" --quiet
python3 - "$work/out" <<'PY'
import json, sys, os
m = json.load(open(os.path.join(sys.argv[1], "manifest.json")))
ran = [s["name"] for s in m["stages"] if s["status"] == "ok" and not s.get("skipped")]
assert not ran, f"re-run should skip every stage, ran {ran}"
PY
# The edit stage on the repaired scan: the earlier stages are up to date, edit and check run.
"$bin/scan2cad" run --from "replay:$src/fixtures/scans/plate" --out "$work/out" --edit "$src/fixtures/edits/plate_widen_holes.s2e" \
  --reference "$ref" --quiet || fail "run --edit exited $?"
for f in edited.ply edited.features.json reports/edit.json; do [[ -s "$work/out/$f" ]] || fail "missing $f"; done
"$bin/s2c-bench-edit" refit "$work/out/edited.ply" "$work/out/repaired.ply" "$src/fixtures/parts/plate.truth.json" \
  --json "$work/edit_refit.json" || fail "refit of the edited plate"
python3 - "$work/out" "$work/edit_refit.json" <<'PY'
import json, sys, os
out = sys.argv[1]
m = json.load(open(os.path.join(out, "manifest.json")))
st = {s["name"]: s for s in m["stages"]}
assert st["acquire"]["status"] == "ok", st["acquire"]
assert st["edit"]["status"] == "ok", st["edit"]
ran = [s["name"] for s in m["stages"] if s["status"] == "ok" and not s.get("skipped")]
assert ran == ["edit", "check", "report"], ran
assert "edited_iso.png" in open(os.path.join(out, "report.html")).read(), "the edited result is pictured"
c = json.load(open(os.path.join(out, "check.json")))
assert c["cad_ready"], c["problems"]
r = json.load(open(sys.argv[2]))
# Refitted independently from the truth-labelled vertices: the four corner holes are Ø7 now.
for h in ["hole_0", "hole_1", "hole_2", "hole_3"]:
    print("%s: r %.4f → %.4f" % (h, r[h]["before"]["radius"], r[h]["radius"]))
    assert abs(r[h]["radius"] - 3.5) <= 0.05, (h, r[h]["radius"])
# The centre hole and the sides are beyond the corner holes' 1-ring: not moved at all.
assert r["hole_center"]["radius"] == r["hole_center"]["before"]["radius"], r["hole_center"]
for s in ["side_xp", "side_xn", "side_yp", "side_yn"]:
    assert r[s]["point"] == r[s]["before"]["point"], s
f = json.load(open(os.path.join(out, "edited.features.json")))
rad = sorted(p["shape"]["radius"] for p in f["patches"] if p["shape"]["type"] == "cylinder" and abs(p["shape"]["radius"] - 3.5) < 0.01)
assert len(rad) >= 4, rad
rep = json.load(open(os.path.join(out, "reports", "edit.json")))
assert rep["counts"]["asserts_passed"] == 2, rep["counts"]
# The first solve holds: no triangle folds, so no ring beyond the first is freed (with Poisson's
# mesh decimated to triangles 8 times longer than high, one at a hole's rim folded, and the next
# ring freed the sides).
solved = [st for st in rep["statements"] if "free_patches" in st]
assert solved and all(st["extra_rings"] == 0 for st in solved), solved
print("edit: corner holes widened, centre hole and sides untouched")
PY
# Laser scans go through the same pipeline.
"$bin/scan2cad" reconstruct "$src/fixtures/scans/shaft_laser" -o "$work/laser.ply" --quiet || fail "laser reconstruct"
[[ -s "$work/laser.ply" ]] || fail "laser mesh missing"
echo "e2e run_fixture_scan: ok"
