#!/usr/bin/env bash
# e2e (issue 9): the report and render on real data from ../shared/data/real/: a real mechanical
# mesh with holes through `scan2cad run` (pictures, added surface, deviation from the mesh as
# scanned), real point clouds through `scan2cad render`, and the page in headless Chromium.
# Skips (77) without the data.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
real="$src/../shared/data/real"
[[ -d "$real" ]] || { echo "no $real: skipped"; exit 77; }
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

shark="$real/defective/cgal_mech-holes-shark.off"
"$bin/scan2cad" run "$shark" --out "$work/shark" --reference "$shark" --quiet || fail "run on the shark exited $?"
python3 - "$work/shark" <<'PY'
import json, os, re, sys
out = sys.argv[1]
page = open(os.path.join(out, "report.html"), encoding="utf-8").read()
images = re.findall(r'<img src="([^"]+)"', page)
for stem in ["mesh", "repaired", "features", "deviation"]:
    assert any(("/%s_iso.png" % stem) in i for i in images), (stem, images)
c = json.load(open(os.path.join(out, "reports", "report.json")))["counts"]
d = c["deviation"]
print("shark: %d faces added by the repair (%.3f mm^2); repaired vs as scanned: mean |d| %.4f, p95 %.4f, max %.4f mm"
      % (c["filled_faces"], c["filled_area_mm2"], d["mean_abs_mm"], d["p95_abs_mm"], d["max_abs_mm"]))
assert c["pictures"] == 9, c  # 4 stages × 2 views + the close-up of the largest filled hole
assert any("repaired_closeup.png" in i for i in images), images
assert c["filled_faces"] > 100, "the shark's holes are filled: the added surface must be found"
# Away from the filled holes the repaired surface lies on the scanned one.
assert d["mean_abs_mm"] < 0.5 * d["max_abs_mm"] and d["mean_abs_mm"] < 0.03, d
assert "Defects found and fixed" in page and "Constraints (" in page
PY
python3 "$src/tests/e2e/report_browser.py" "$work/shark/report.html" "$work/shark_screenshot.png"

# Real point clouds (no faces): discs where the points are, background elsewhere.
for cloud in cgal_cylinders_points cgal_spheres_points; do
  "$bin/scan2cad" render "$real/cad/$cloud.ply" -o "$work/$cloud.png" --size 400x300 --quiet || fail "render $cloud"
  python3 - "$work/$cloud.png" "$src/tests/e2e" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from report_browser import decode_png
w, h, ch, rows = decode_png(open(sys.argv[1], "rb").read())
blue = sum(1 for r in rows for x in range(0, w * ch, ch) if r[x + 2] > r[x] + 40)
print("%s: %dx%d, %.1f%% of the pixels are points" % (sys.argv[1].split("/")[-1], w, h, 100.0 * blue / (w * h)))
assert blue > 0.01 * w * h, blue
PY
done
echo "e2e report_real: ok"
