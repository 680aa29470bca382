#!/usr/bin/env bash
# Issue 5 benchmarks of the features stage; prints Markdown tables on stdout, keeps every output
# (tables, verbose logs, reconstructed meshes) in OUT. Builds nothing.
#
#   bench/run_features.sh [BUILD_DIR]        (default build/; run from anywhere)
#
# Needs BUILD_DIR/bin/s2c-bench-features; optional s2c-bench-cgal-ransac (CGAL found) and, for the
# scans section, scan2cad-reconstruct / scan2cad-repair. Build them with
#   ninja -C BUILD_DIR s2c-bench-features s2c-bench-cgal-ransac scan2cad scan2cad-reconstruct scan2cad-repair
#
# Sections (SECTIONS="selfcheck sweep ransac scans speed", default all):
#   selfcheck  s2c-bench-features selfcheck (the evaluation judges the truth itself as perfect and
#              a perturbed copy as losing exactly what was perturbed)
#   sweep      s2c-bench-features sweep: each part's OpenSCAD mesh ("clean CAD") and its refinement
#              (max edge = bbox diagonal / DIV) with Gaussian noise σ ∈ SIGMAS × mean edge length
#   ransac     s2c-bench-cgal-ransac sweep: ours against CGAL Efficient RANSAC (defaults, SAMPLES
#              points, RUNS seeds) on the same inputs, same run
#   scans      each fixture scan (fixtures/scans/NAME) → scan2cad reconstruct → scan2cad repair with
#              defaults (the stages `scan2cad run` runs before features) → repaired.ply, kept in
#              OUT/scan_NAME and reused when present; then s2c-bench-features mesh and
#              s2c-bench-cgal-ransac mesh on it against fixtures/parts/PART.truth.json
#   speed      s2c-bench-features speed: the CGAL fandisk subdivided to ≥ VERTICES vertices, analyze()
#              best of 3 and the first run; the CGAL anchor subdivided to 0.97 M vertices; the
#              pocket scan's repaired mesh when the scans section left one in OUT
# Every bench command runs under `timeout $TIMEOUT` (default 1800 s); a row that timed out is
# reported as such.
#
# Environment: OUT=DIR (default: a new /tmp directory), PARTS="plate shaft bracket pocket",
# SCANS="plate shaft bracket pocket shaft_laser", SIGMAS=0,0.1,0.2,0.3, DIV=100, SEED=1,
# SAMPLES=100000, RUNS=3, VERTICES=1000000, TIMEOUT=1800.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root" || exit 2
build="${1:-build}"
bin="$build/bin"
out="${OUT:-$(mktemp -d /tmp/s2c-bench-features.XXXXXX)}"
mkdir -p "$out"
sections="${SECTIONS:-selfcheck sweep ransac scans speed}"
parts="${PARTS:-plate shaft bracket pocket}"
scans="${SCANS:-plate shaft bracket pocket shaft_laser}"
sigmas="${SIGMAS:-0,0.1,0.2,0.3}"
div="${DIV:-100}"
seed="${SEED:-1}"
samples="${SAMPLES:-100000}"
runs="${RUNS:-3}"
vertices="${VERTICES:-1000000}"
limit="${TIMEOUT:-1800}"
names="$(echo $parts | tr ' ' ',')"

if [[ ! -x "$bin/s2c-bench-features" ]]; then
  echo "run_features.sh: $bin/s2c-bench-features missing; build it: ninja -C $build s2c-bench-features [s2c-bench-cgal-ransac]" >&2
  exit 2
fi
have_ransac=0
[[ -x "$bin/s2c-bench-cgal-ransac" ]] && have_ransac=1

echo "outputs in $out" >&2
echo "$(nproc) cores; load average at start: $(cut -d' ' -f1-3 /proc/loadavg); $(date -u +%Y-%m-%dT%H:%MZ)"
echo

# run NAME CMD...: stdout → OUT/NAME.md (and ours), stderr → OUT/NAME.log; notes a timeout.
run() {
  local name="$1"
  shift
  local t0=$SECONDS
  timeout "$limit" "$@" >"$out/$name.md" 2>"$out/$name.log"
  local rc=$?
  grep '^|' "$out/$name.md"
  grep -v '^|' "$out/$name.md" | grep -v '^\[' >&2
  if [[ $rc -eq 124 ]]; then
    echo "*$name: timed out after ${limit} s (rows above finished; log $out/$name.log)*"
  elif [[ $rc -ne 0 ]]; then
    echo "*$name: exit code $rc (log $out/$name.log)*"
  fi
  echo "$name: $((SECONDS - t0)) s, exit $rc" >&2
  return 0
}

for section in $sections; do
  case "$section" in
    selfcheck)
      echo "### selfcheck"
      echo
      timeout "$limit" "$bin/s2c-bench-features" selfcheck >"$out/selfcheck.txt" 2>"$out/selfcheck.log"
      echo "exit $?: $(tail -1 "$out/selfcheck.txt")"
      echo
      ;;
    sweep)
      echo "### noise sweep (ours)"
      echo
      run sweep "$bin/s2c-bench-features" sweep --names "$names" --sigma "$sigmas" --div "$div" --seed "$seed" --verbose
      echo
      ;;
    ransac)
      if [[ $have_ransac -eq 0 ]]; then
        echo "*ransac: s2c-bench-cgal-ransac not built (no CGAL), skipped*"
        continue
      fi
      echo "### ours vs CGAL Efficient RANSAC (same inputs, same run)"
      echo
      run ransac "$bin/s2c-bench-cgal-ransac" sweep --names "$names" --sigma "$sigmas" --div "$div" --seed "$seed" \
        --samples "$samples" --runs "$runs" --verbose
      echo
      ;;
    scans)
      echo "### meshes reconstructed from the fixture scans"
      echo
      for scan in $scans; do
        part="${scan%_laser}"
        dir="$out/scan_$scan"
        mkdir -p "$dir"
        if [[ ! -s "$dir/repaired.ply" ]]; then
          if [[ ! -x "$bin/scan2cad-reconstruct" || ! -x "$bin/scan2cad-repair" ]]; then
            echo "*scan $scan: scan2cad-reconstruct / scan2cad-repair not built, skipped*"
            continue
          fi
          # shellcheck disable=SC2086
          "$bin/scan2cad" reconstruct "fixtures/scans/$scan" -o "$dir/mesh.ply" -q ${RECON_ARGS:-} 2>"$dir/reconstruct.log" &&
            "$bin/scan2cad" repair "$dir/mesh.ply" -o "$dir/repaired.ply" -q 2>"$dir/repair.log" ||
            { echo "*scan $scan: reconstruct/repair failed (logs in $dir)*"; continue; }
        fi
        rm -f "$dir/features.json"
        run "scan_$scan" "$bin/s2c-bench-features" mesh "$dir/repaired.ply" "fixtures/parts/$part.truth.json" \
          --features-out "$dir/features.json" --verbose
        if [[ $have_ransac -eq 1 ]]; then
          # ours = the features just computed (or none if analyze timed out), CGAL on the same mesh
          ours=(--skip-ours)
          [[ -s "$dir/features.json" ]] && ours=(--features "$dir/features.json")
          run "scan_${scan}_ransac" "$bin/s2c-bench-cgal-ransac" mesh "$dir/repaired.ply" "fixtures/parts/$part.truth.json" \
            "${ours[@]}" --noise 0.05 --samples "$samples" --runs "$runs" --verbose
        fi
        echo
      done
      ;;
    speed)
      echo "### speed"
      echo
      run speed "$bin/s2c-bench-features" speed --vertices "$vertices"
      echo
      # A second CAD mesh near a million vertices: the CGAL anchor, subdivided four times
      # (972,538 vertices; its faceted round parts become many flat patches).
      run speed_anchor "$bin/s2c-bench-features" speed --mesh ../shared/data/real/cad/cgal_anchor_dense.off \
        --vertices 900000
      echo
      # The pipeline's own input: a scan's repaired mesh (the scans section's, when it ran).
      if [[ -s "$out/scan_pocket/repaired.ply" ]]; then
        run speed_scan_pocket "$bin/s2c-bench-features" speed --mesh "$out/scan_pocket/repaired.ply" --vertices 0
        echo
      fi
      ;;
    *)
      echo "run_features.sh: unknown section $section" >&2
      ;;
  esac
done
