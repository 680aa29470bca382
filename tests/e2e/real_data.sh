#!/usr/bin/env bash
# e2e on real data from ../shared/data/real (issue 3): registration of the Stanford bunny scans
# without poses against bun.conf, meshing PCL's organised stereo cloud (NaNs included), the PCL
# Kinect frames and one TUM frame. Skips (exit 77) when the shared data is absent.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
real="$src/../shared/data/real"
[[ -d "$real" ]] || { echo "no $real: skipped"; exit 77; }
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/s2c-bench-bunny" "$real/scans/stanford_bunny" > "$work/bunny.json"
python3 - "$work/bunny.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("bunny: max rotation error %.3f deg, max translation error %.3f mm" % (r["max_rotation_error_deg"], r["max_translation_error_mm"]))
assert r["max_rotation_error_deg"] <= 1.0, r
assert r["max_translation_error_mm"] <= 1.0, r
assert not any(v["rejected"] for v in r["views"]), r
PY

check_mesh() {  # mesh min-faces
  [[ -s "$1" ]] || fail "missing $1"
  "$bin/scan2cad" check "$1" --no-self-intersections > "$work/check.json"
  python3 - "$work/check.json" "$2" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
assert c["faces"] >= int(sys.argv[2]), c["faces"]
assert c["nonmanifold_edges"] == 0, c
PY
}
"$bin/scan2cad" reconstruct "$real/scans/pcl/table_scene_mug_stereo_textured.pcd" --input-unit-mm 1000 \
  --depth 8 -o "$work/mug.ply" --quiet
check_mesh "$work/mug.ply" 10000
"$bin/scan2cad" reconstruct "$real/rgbd/pcl_kinect_seq" --intrinsics 525,525,320,240 --depth-unit-mm 1 \
  --depth 8 -o "$work/kinect.ply" --report "$work/kinect.json" --quiet
check_mesh "$work/kinect.ply" 10000
python3 - "$work/kinect.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["counts"]["frames"] == 3 and not any(v["rejected"] for v in r["views"]), r["views"]
PY
"$bin/scan2cad" reconstruct "$real/rgbd/tum_single" --intrinsics 525,525,319.5,239.5 --depth-unit-mm 0.2 \
  --depth 8 -o "$work/tum.ply" --quiet
check_mesh "$work/tum.ply" 10000
# The imls mesher on the same noisy frame: its support widens with the measured noise, so the
# band holds together (468 boundary loops; 5,789 at the clean scans' 2.5 voxels).
"$bin/scan2cad" reconstruct "$real/rgbd/tum_single" --intrinsics 525,525,319.5,239.5 --depth-unit-mm 0.2 \
  --method imls -o "$work/tum_imls.ply" --report "$work/tum_imls.json" --quiet
check_mesh "$work/tum_imls.ply" 10000
"$bin/scan2cad" check "$work/tum_imls.ply" --no-self-intersections > "$work/check_imls.json"
python3 - "$work/check_imls.json" "$work/tum_imls.json" <<'PY'
import json, sys
c, r = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
voxel, noise = r["parameters"]["voxel_mm"], r["counts"]["imls_noise_mm"]
print("imls TUM frame: noise %.2f voxel, support %.2f voxels, %d boundary loops, %d components"
      % (noise / voxel, r["parameters"]["imls_support_mm"] / voxel, c["boundary_loops"], c["components"]))
assert noise > 0.45 * voxel and r["parameters"]["imls_support_mm"] > 4 * voxel, r
assert c["boundary_loops"] < 1500 and c["components"] < 500, c
PY
echo "e2e real_data: ok"
