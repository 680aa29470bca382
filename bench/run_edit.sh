#!/usr/bin/env bash
# Issue 6 benchmarks of the edit stage; prints Markdown tables on stdout, keeps every output in OUT.
# Builds nothing.
#
#   bench/run_edit.sh [BUILD_DIR]        (default build/; run from anywhere)
#
# Needs BUILD_DIR/bin/{s2c-bench-edit, scan2cad, scan2cad-features, scan2cad-edit} and, for the
# scans section, scan2cad-reconstruct / scan2cad-repair:
#   ninja -C BUILD_DIR s2c-bench-edit scan2cad scan2cad-features scan2cad-edit scan2cad-reconstruct scan2cad-repair
#
# Sections (SECTIONS="speed scripts", default both):
#   speed    s2c-bench-edit speed: the plate refined to each of VERTICES; widen a corner hole in
#            STEPS steps (equal_radius takes the other three); restricted ARAP (ours) and ARAP over
#            the whole mesh (the comparison) in the same run; accuracy by refitting the truth holes
#   scripts  each fixtures/edits script on the part's OpenSCAD mesh and on its repaired scan
#            (fixtures/scans/PART → reconstruct → repair, kept in OUT/scan_PART and reused): time,
#            the requested value against the value refitted from the truth-labelled vertices
#            (s2c-bench-edit refit), the largest residual of the truth's constraints on the
#            refitted primitives before and after and the largest growth of one of them (what the
#            edit added), and scan2cad check
# Environment: OUT=DIR (default: a new /tmp directory), VERTICES=50000,1000000, STEPS=20.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root" || exit 2
build="${1:-build}"
bin="$build/bin"
out="${OUT:-$(mktemp -d /tmp/s2c-bench-edit.XXXXXX)}"
mkdir -p "$out"
sections="${SECTIONS:-speed scripts}"
echo "<!-- bench/run_edit.sh at $(git rev-parse --short HEAD 2>/dev/null), $(date -u +%F), $(nproc) cores; outputs in $out -->"

if [[ " $sections " == *" speed "* ]]; then
  echo
  echo "### speed: restricted ARAP against whole-mesh ARAP (same run)"
  echo
  "$bin/s2c-bench-edit" speed --vertices "${VERTICES:-50000,1000000}" --steps "${STEPS:-20}" --json "$out/speed.json" \
    2> "$out/speed.log"
fi

# One script on one mesh: features, edit (timed), refit, check → one table row.
edit_row() {  # part input-label mesh script expectation(id:property:value)
  local part="$1" label="$2" mesh="$3" script="$4" expect="$5"
  local name; name="$(basename "$script" .s2e)_$(echo "$label" | tr ' ' '_')"
  local d="$out/$name"; mkdir -p "$d"
  "$bin/scan2cad" features "$mesh" -o "$d/features.json" --quiet || { echo "| $part | $label | $(basename "$script") | features failed |"; return; }
  local t0 t1 rc
  t0=$(date +%s.%N)
  "$bin/scan2cad" edit "$mesh" --features "$d/features.json" --script "$script" -o "$d/edited.ply" \
    --features-out "$d/edited.features.json" --report "$d/edit.json" 2> "$d/edit.log"
  rc=$?
  t1=$(date +%s.%N)
  if ((rc != 0)); then echo "| $part | $label | $(basename "$script") | exit $rc: $(tail -c 200 "$d/edit.log" | tr '\n|' ' /') |"; return; fi
  "$bin/s2c-bench-edit" refit "$d/edited.ply" "$mesh" "fixtures/parts/$part.truth.json" --json "$d/refit.json" 2>> "$d/edit.log"
  "$bin/scan2cad" check "$d/edited.ply" > "$d/check.json" 2>> "$d/edit.log"
  python3 - "$d" "fixtures/parts/$part.truth.json" "$part" "$label" "$(basename "$script")" "$expect" "$t0" "$t1" <<'PY'
import json, math, sys
d, truth_path, part, label, script, expect, t0, t1 = sys.argv[1:9]
r = json.load(open(d + "/refit.json"))
truth = json.load(open(truth_path))
rep = json.load(open(d + "/edit.json"))
check = json.load(open(d + "/check.json"))
def unit(v):
    n = math.sqrt(sum(x * x for x in v)); return [x / n for x in v]
def angle(a, b):
    a, b = unit(a), unit(b)
    c = abs(sum(x * y for x, y in zip(a, b)))
    s = math.sqrt(sum(x * x for x in [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]))
    return math.degrees(math.atan2(s, c))
def axis_dist(p, q, d):
    d = unit(d); w = [x - y for x, y in zip(p, q)]; t = sum(x * y for x, y in zip(w, d))
    return math.sqrt(max(0.0, sum(x * x for x in w) - t * t))
def residual(c, key):
    m = [r.get(x, {}).get(key) if key else r.get(x) for x in c["members"]]
    if any(x is None for x in m): return None
    k = c["kind"]
    if k == "parallel": return max(angle(m[0]["dir"], x["dir"]) for x in m[1:]), 0.0
    if k == "perpendicular": return abs(90 - angle(m[0]["dir"], m[1]["dir"])), 0.0
    if k == "equal_radius" and all("radius" in x for x in m):
        return 0.0, max(x["radius"] for x in m) - min(x["radius"] for x in m)
    if k == "coaxial" and all(x["type"] in ("cylinder", "cone") for x in m):
        return (max(angle(m[0]["dir"], x["dir"]) for x in m[1:]),
                max(axis_dist(x["point"], m[0]["point"], m[0]["dir"]) for x in m[1:]))
    return None
def worst(key):
    a = l = 0.0
    for c in truth["constraints"]:
        x = residual(c, key)
        if x: a, l = max(a, x[0]), max(l, x[1])
    return a, l
def growth():  # what the edit added: the largest increase of one constraint's residual
    a = l = 0.0
    for c in truth["constraints"]:
        x, y = residual(c, "before"), residual(c, None)
        if x and y: a, l = max(a, y[0] - x[0]), max(l, y[1] - x[1])
    return a, l
# expectation "id:property:value" (e.g. hole_0:radius:3.5)
eid, prop, want = expect.split(":")
got = None
if eid in r:
    got = r[eid]["radius"] if prop == "radius" else r[eid]["point"][2] if prop == "z" else None
err = abs(got - float(want)) if got is not None else float("nan")
ab, lb = worst("before")
aa, la = worst(None)
st = rep["statements"]
prop_steps = sum(len(s.get("propagation", [])) for s in st)
free = max((s.get("free_vertices", 0) for s in st), default=0)
broken = rep["counts"]["broken_constraints"]
ga, gl = growth()
carried = sum(s.get("carried_patches", 0) for s in st)
print("| %s | %s | %s | %.2f s | %s %s = %s → %.4f (err %.4f mm) | %.3g° / %.3g mm → %.3g° / %.3g mm | %.2g° / %.2g mm | %d | %d | %d | %d | %s |" % (
    part, label, script, float(t1) - float(t0), eid, prop, want, got if got is not None else float("nan"), err,
    ab, lb, aa, la, ga, gl, prop_steps, carried, free, broken, "yes" if check["cad_ready"] else "NO"))
PY
}

if [[ " $sections " == *" scripts "* ]]; then
  echo
  echo "### scripts on the fixture parts: requested vs refitted, truth constraints, CAD-ready"
  echo
  echo "| part | input | script | time (incl. read, check, write) | requested → refitted | truth constraint residual before → after (worst) | largest growth of one constraint's residual | propagation steps | carried crumbs | free vertices | broken | CAD-ready |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
  declare -A expect=(
    [plate_widen_holes]="hole_1:radius:3.5"
    [plate_raise_top]="top:z:10"
    [shaft_thicker]="shaft_body:radius:11"
  )
  for script in fixtures/edits/*.s2e; do
    s=$(basename "$script" .s2e); part=${s%%_*}
    edit_row "$part" "OpenSCAD" "fixtures/parts/$part.stl" "$script" "${expect[$s]}"
    scan="$out/scan_$part"
    if [[ ! -s "$scan/repaired.ply" ]]; then
      mkdir -p "$scan"
      "$bin/scan2cad" reconstruct "fixtures/scans/$part" -o "$scan/mesh.ply" --quiet 2> "$scan/log" &&
        "$bin/scan2cad" repair "$scan/mesh.ply" -o "$scan/repaired.ply" --quiet 2>> "$scan/log"
    fi
    if [[ -s "$scan/repaired.ply" ]]; then
      edit_row "$part" "repaired scan" "$scan/repaired.ply" "$script" "${expect[$s]}"
    else
      echo "| $part | repaired scan | $(basename "$script") | reconstruct/repair failed (see $scan/log) |"
    fi
  done
fi
