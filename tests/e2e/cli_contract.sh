#!/usr/bin/env bash
# e2e: the command-line contract of DESIGN.md for every executable of the build:
# --help exits 0, bad usage exits 2, bad input exits 2 with the file named and no output.
set -uo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }
expect_rc() {  # expected-code description command...
  local want="$1" what="$2"; shift 2
  "$@" >"$work/stdout" 2>"$work/stderr"; local rc=$?
  [[ $rc == "$want" ]] || fail "$what: exit $rc, expected $want ($(head -c 300 "$work/stderr"))"
}

expect_rc 0 "scan2cad --help" "$bin/scan2cad" --help
grep -q "simulate" "$work/stdout" || fail "scan2cad --help does not list stages"
expect_rc 2 "scan2cad without a stage" "$bin/scan2cad"
expect_rc 2 "unknown stage" "$bin/scan2cad" frobnicate

printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n' > "$work/bad.off"
cp "$work/bad.off" "$work/bad.copy"
for exe in "$bin"/scan2cad-*; do
  name=$(basename "$exe"); stage=${name#scan2cad-}
  expect_rc 0 "$name --help" "$exe" --help
  grep -qi "usage" "$work/stdout" || fail "$name --help prints no usage"
  expect_rc 2 "$name with no arguments" "$exe"
  expect_rc 2 "$name --no-such-option" "$exe" --no-such-option
done

# Bad input: exit 2, the file named, no output written, input untouched.
expect_rc 2 "check on a bad mesh" "$bin/scan2cad" check "$work/bad.off"
grep -q "bad.off" "$work/stderr" || fail "check's message does not name the file"
expect_rc 2 "simulate on a bad mesh" "$bin/scan2cad" simulate "$work/bad.off" --out "$work/sim_out"
[[ ! -e "$work/sim_out" ]] || fail "simulate left output after bad input"
expect_rc 2 "reconstruct on a missing stream" "$bin/scan2cad" reconstruct "$work/nowhere" -o "$work/rec.ply"
[[ ! -e "$work/rec.ply" ]] || fail "reconstruct left output after bad input"
mkdir -p "$work/badstream"; cp -r "$src/fixtures/scans/plate/." "$work/badstream/"
printf '0.0 depth/000000.png\n1.0 depth/999.png\n' > "$work/badstream/depth.txt"
expect_rc 2 "reconstruct with a missing frame" "$bin/scan2cad" reconstruct "$work/badstream" -o "$work/rec.ply"
grep -q "999.png" "$work/stderr" || fail "reconstruct's message does not name the frame"
[[ ! -e "$work/rec.ply" ]] || fail "reconstruct left output after a bad frame"
expect_rc 2 "repair on a bad mesh" "$bin/scan2cad" repair "$work/bad.off" -o "$work/rep.ply"
grep -q "bad.off" "$work/stderr" || fail "repair's message does not name the file"
[[ ! -e "$work/rep.ply" ]] || fail "repair left output after bad input"
expect_rc 2 "repair to an unknown format" "$bin/scan2cad" repair "$src/fixtures/parts/plate.stl" -o "$work/rep.xyz"
expect_rc 2 "repair onto its own input" "$bin/scan2cad" repair "$work/bad.off" -o "$work/bad.off"
expect_rc 2 "repair with --voxel and --resolution" "$bin/scan2cad" repair "$src/fixtures/parts/plate.stl" -o "$work/rep.ply" \
  --voxel 0.5 --resolution 100
# render and report: bad input exits 2 naming what is wrong, and leaves no picture or page.
expect_rc 2 "render a bad mesh" "$bin/scan2cad" render "$work/bad.off" -o "$work/bad.png"
grep -q "bad.off" "$work/stderr" || fail "render's message does not name the file"
[[ ! -e "$work/bad.png" ]] || fail "render left a picture after bad input"
expect_rc 2 "render to a non-PNG name" "$bin/scan2cad" render "$src/fixtures/parts/plate.stl" -o "$work/plate.jpg"
expect_rc 2 "render from an unknown view" "$bin/scan2cad" render "$src/fixtures/parts/plate.stl" -o "$work/p.png" --view sideways
grep -q "iso" "$work/stderr" || fail "render does not list the views"
expect_rc 2 "render with a bad size" "$bin/scan2cad" render "$src/fixtures/parts/plate.stl" -o "$work/p.png" --size 10x
[[ ! -e "$work/p.png" ]] || fail "render left a picture after bad usage"
expect_rc 0 "render a part" "$bin/scan2cad" render "$src/fixtures/parts/plate.stl" -o "$work/p.png" --size 320x240 --view top
[[ $(head -c 4 "$work/p.png" | tail -c 3) == PNG ]] || fail "render wrote no PNG"
expect_rc 2 "report on a folder without a manifest" "$bin/scan2cad" report "$work" -o "$work/r.html"
grep -q "manifest.json" "$work/stderr" || fail "report does not say what a run folder needs"
[[ ! -e "$work/r.html" && ! -e "$work/r_files" ]] || fail "report left output after bad input"
mkdir -p "$work/badrun"; printf '{"stages": [' > "$work/badrun/manifest.json"
expect_rc 2 "report on a torn manifest" "$bin/scan2cad" report "$work/badrun"
grep -q "badrun/manifest.json" "$work/stderr" || fail "report does not name the torn manifest"
[[ -z $(ls -A "$work/badrun" | grep -v manifest.json) ]] || fail "report left files after a torn manifest"
expect_rc 2 "run with a missing reference" "$bin/scan2cad" run "$src/fixtures/parts/plate.stl" --out "$work/runref" \
  --reference "$work/nowhere.stl"
grep -q "nowhere.stl" "$work/stderr" || fail "run does not name the missing reference"
[[ ! -e "$work/runref" ]] || fail "run made its folder before refusing the reference"
# acquire: live devices need a calibration; bad sources and corrupt replays exit 2, leave nothing.
expect_rc 2 "acquire without --calibration" "$bin/scan2cad" acquire --from v4l2:/dev/video0 --out "$work/acq"
grep -q "calibration" "$work/stderr" || fail "acquire does not ask for --calibration"
expect_rc 2 "acquire from an unknown source" "$bin/scan2cad" acquire --from camera0 --out "$work/acq"
grep -q "v4l2:/dev/videoN" "$work/stderr" || fail "acquire does not list the source forms"
printf '%%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 525., 0., 319.5, 0., 525., 239.5, 0., 0., 1. ]\ndist_coeffs: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0., 0., 0., 0., 0. ]\n' > "$work/cam_nounit.yaml"
expect_rc 2 "acquire with a calibration missing a key" "$bin/scan2cad" acquire --from v4l2:/dev/video0 \
  --calibration "$work/cam_nounit.yaml" --out "$work/acq"
grep -q "depth_unit_mm" "$work/stderr" || fail "acquire does not name the missing calibration key"
printf 'depth_unit_mm: 1.\n' >> "$work/cam_nounit.yaml"
expect_rc 4 "acquire from a camera that is not there" "$bin/scan2cad" acquire --from v4l2:/dev/video-s2c-none \
  --calibration "$work/cam_nounit.yaml" --out "$work/acq"
grep -q "no such device" "$work/stderr" || fail "acquire does not say the camera is missing"
[[ ! -e "$work/acq" ]] || fail "acquire left output when the device was missing"
expect_rc 0 "acquire a replay" "$bin/scan2cad" acquire --from "replay:$src/fixtures/scans/plate" --out "$work/acq" --frames 3
[[ $(grep -vc '^#' "$work/acq/depth.txt") == 3 ]] || fail "acquire --frames 3 did not record 3 frames"
expect_rc 2 "acquire into a folder that holds something" "$bin/scan2cad" acquire --from "replay:$src/fixtures/scans/plate" \
  --out "$work/acq"
[[ $(grep -vc '^#' "$work/acq/depth.txt") == 3 ]] || fail "acquire overwrote an existing recording"
rm -rf "$work/acq" "$work/corrupt"; cp -r "$src/fixtures/scans/plate" "$work/corrupt"
head -c 500 "$src/fixtures/scans/plate/depth/000004.png" > "$work/corrupt/depth/000004.png"
expect_rc 2 "acquire a replay with a corrupt frame" "$bin/scan2cad" acquire --from "replay:$work/corrupt" --out "$work/acq"
grep -q "000004.png" "$work/stderr" || fail "acquire does not name the corrupt frame"
[[ ! -e "$work/acq" ]] || fail "acquire left a partial recording of a corrupt replay"
expect_rc 2 "run with both INPUT and --from" "$bin/scan2cad" run "$src/fixtures/scans/plate" --from replay:x --out "$work/r"

# A mesh that cannot become CAD-ready under the asked strategy: exit 3, report written, no mesh.
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > "$work/tri.off"
expect_rc 3 "repair --strategy surface --holes none on an open triangle" "$bin/scan2cad" repair "$work/tri.off" \
  -o "$work/rep.ply" --strategy surface --holes none --report "$work/rep.json"
[[ ! -e "$work/rep.ply" ]] || fail "repair wrote a mesh that is not CAD-ready"
[[ -s "$work/rep.json" ]] || fail "repair wrote no report on failure"
if [[ -x "$bin/scan2cad-features" ]]; then
  expect_rc 2 "features on a bad mesh" "$bin/scan2cad" features "$work/bad.off" -o "$work/f.json"
  grep -q "bad.off" "$work/stderr" || fail "features' message does not name the file"
  [[ ! -e "$work/f.json" ]] || fail "features left output after bad input"
  printf 'OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n' > "$work/nan.off"
  expect_rc 2 "features on a mesh with NaN" "$bin/scan2cad" features "$work/nan.off" -o "$work/f.json"
  [[ ! -e "$work/f.json" ]] || fail "features left output after a NaN mesh"
  expect_rc 2 "features --segments-out not PLY" "$bin/scan2cad" features "$src/fixtures/parts/plate.stl" \
    -o "$work/f.json" --segments-out "$work/seg.stl"
  [[ ! -e "$work/f.json" ]] || fail "features wrote output after a bad option"
  expect_rc 2 "features --min-angle out of range" "$bin/scan2cad" features "$src/fixtures/parts/plate.stl" \
    -o "$work/f.json" --min-angle 500
  # A lone open triangle has no features worth the name: an honest result, not an error.
  expect_rc 0 "features on an open triangle" "$bin/scan2cad" features "$work/tri.off" -o "$work/f.json"
  python3 -c 'import json,sys; f=json.load(open(sys.argv[1])); assert f["format"]=="scan2cad.features/1"' \
    "$work/f.json" || fail "features on an open triangle wrote no valid features.json"
fi
if [[ -x "$bin/scan2cad-edit" ]]; then
  "$bin/scan2cad" features "$src/fixtures/parts/plate.stl" -o "$work/plate.f.json" --quiet || fail "features of the plate"
  plate="$src/fixtures/parts/plate.stl"; feats="$work/plate.f.json"
  printf 'let h = select cylinder nearest [22, 12, 4]\nset h.radius = 3.5\nexport "%s"\n' "$work/exp.stl" > "$work/ok.s2e"
  expect_rc 0 "edit a plate hole" "$bin/scan2cad" edit "$plate" --features "$feats" --script "$work/ok.s2e" \
    -o "$work/e.ply" --features-out "$work/e.json"
  [[ -s "$work/e.ply" && -s "$work/e.json" && -s "$work/exp.stl" ]] || fail "edit wrote not all of its outputs"
  # The features written for the edited mesh belong to it: a second edit accepts them.
  printf 'let h = select cylinder where radius ~ 3.5 +- 0.01\nassert h.count == 4\n' > "$work/again.s2e"
  expect_rc 0 "edit the edited mesh with its features" "$bin/scan2cad" edit "$work/e.ply" --features "$work/e.json" \
    --script "$work/again.s2e" --dry-run
  rm -f "$work/e.ply" "$work/e.json" "$work/exp.stl"
  expect_rc 2 "edit with features of another mesh" "$bin/scan2cad" edit "$src/fixtures/parts/pocket.stl" \
    --features "$feats" --script "$work/ok.s2e" -o "$work/e.ply"
  grep -q "sha256" "$work/stderr" || fail "edit's hash message does not say why"
  printf 'let h = select cylinder nearest [22, 12, 4]\nmove h [0, 0, 1]\n' > "$work/syntax.s2e"
  expect_rc 2 "edit script with a syntax error" "$bin/scan2cad" edit "$plate" --features "$feats" \
    --script "$work/syntax.s2e" -o "$work/e.ply"
  grep -q "syntax.s2e:2:8: expected 'by'" "$work/stderr" || fail "edit's syntax error names no line:column ($(cat "$work/stderr"))"
  printf 'let h = select cylinder nearest [22, 12, 4]\nset h.radius = 3.5\nexport "%s"\nassert h.radius ~ 4 +- 0.05\n' \
    "$work/exp.stl" > "$work/assert.s2e"
  expect_rc 3 "edit script with a failing assert" "$bin/scan2cad" edit "$plate" --features "$feats" \
    --script "$work/assert.s2e" -o "$work/e.ply" --features-out "$work/e.json"
  grep -q "assert.s2e:4" "$work/stderr" || fail "edit's failed assert names no line"
  [[ ! -e "$work/e.ply" && ! -e "$work/e.json" && ! -e "$work/exp.stl" ]] || fail "edit wrote output after a failed assert"
  expect_rc 0 "edit --dry-run" "$bin/scan2cad" edit "$plate" --features "$feats" --script "$work/ok.s2e" --dry-run
  grep -q "propagates" "$work/stdout" || fail "edit --dry-run does not say what propagates"
  [[ ! -e "$work/exp.stl" ]] || fail "edit --dry-run wrote an export"
  expect_rc 2 "edit --set of an unknown parameter" "$bin/scan2cad" edit "$plate" --features "$feats" \
    --script "$work/ok.s2e" -o "$work/e.ply" --set nope=3
  expect_rc 2 "edit onto its own input" "$bin/scan2cad" edit "$work/bad.off" --features "$feats" \
    --script "$work/ok.s2e" -o "$work/bad.off"
  [[ ! -e "$work/e.ply" ]] || fail "edit wrote output after bad input"
fi
expect_rc 2 "run on a missing input" "$bin/scan2cad" run "$work/nothing.stl" --out "$work/run_out"
cmp -s "$work/bad.off" "$work/bad.copy" || fail "an input was modified"
ls -a "$work" | grep -q "\.tmp-" && fail "a temporary file was left behind"

if ((failures)); then echo "e2e cli_contract: $failures failures" >&2; exit 1; fi
echo "e2e cli_contract: ok"
