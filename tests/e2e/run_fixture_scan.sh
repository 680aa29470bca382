#!/usr/bin/env bash
# e2e: `scan2cad run` on a bundled recorded scan, as the README's demo does.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/scan2cad" run "$src/fixtures/scans/plate" --out "$work/out" --quiet || fail "run exited $?"
for f in manifest.json cloud.ply mesh.ply check.json reports/reconstruct.json; do
  [[ -s "$work/out/$f" ]] || fail "missing $f"
done
python3 - "$work/out" <<'PY'
import json, sys, os
out = sys.argv[1]
m = json.load(open(os.path.join(out, "manifest.json")))
st = {s["name"]: s for s in m["stages"]}
assert st["reconstruct"]["status"] == "ok", st["reconstruct"]
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
print("manifest ok:", [(s["name"], s["status"]) for s in m["stages"]])
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
