#!/bin/bash
# Large meshes: the analysis on the working mesh (the default) against the whole mesh
# (--working-vertices 0), both against the fixture parts' truth (bench/README.md, "a working
# mesh for large noisy meshes" and "smooth meshes on a working mesh").
#   bench/features_working.sh [BUILD_DIR]
# Environment: OUT (default /tmp/s2c-features-working), SECTIONS (default "noisy smooth"),
# FULL=0 skips the whole-mesh runs (3-17 s each).
#   noisy   each fixture part (PARTS, default "plate shaft bracket pocket") refined to about a
#           million vertices (DIVS below: the diagonal over the longest edge), then given Gaussian
#           noise of σ mean edges (SIGMAS, default "0.1 0.2 0.3"; `s2c-bench-features inputs`,
#           seed 1);
#   smooth  the fixture scans (SCANS, default all five) reconstructed by Poisson at octree depth 9
#           without decimation (0.40-0.87 M vertices; RECON_ARGS, default "--depth 9 --simplify
#           0"), then repaired: smooth surfaces, noise 1-3 % of the edge. Kept in OUT and reused.
#           SEED=N (default 1, the bundled scans) records the scans afresh with the virtual
#           scanner's seed N first, as scripts/make-fixture-scans.sh does with seed 1 (stop 54's
#           second set: SEED=2).
# Per mesh it prints one row per mode: vertices, the analysis' time (the report's steps from arrays
# to groups, s), the whole command's time and peak memory (/usr/bin/time), the working mesh's
# vertices, and the quality columns of `s2c-bench-features mesh`.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "${1:-$here/build}" && pwd)/bin
out=${OUT:-/tmp/s2c-features-working}
mkdir -p "$out"
declare -A divs=([plate]=560 [shaft]=620 [bracket]=510 [pocket]=480)

# measure PART LABEL MESH DIR: both modes on MESH, one row each.
measure() {
  local part=$1 label=$2 mesh=$3 dir=$4
  local modes="working"
  [[ ${FULL:-1} == 0 ]] || modes="working full"
  for mode in $modes; do
    local wv=()
    [[ $mode == full ]] && wv=(--working-vertices 0)
    /usr/bin/time -f "%e %M" -o "$dir/$mode.time" "$bin/scan2cad-features" "$mesh" -o "$dir/$mode.json" \
      --report "$dir/$mode.report.json" -q "${wv[@]}"
    "$bin/s2c-bench-features" mesh "$mesh" "$here/fixtures/parts/$part.truth.json" --features "$dir/$mode.json" \
      --json "$dir/$mode.eval.json" >/dev/null
    python3 - "$part" "$label" "$mode" "$dir" "$mesh" <<'PY'
import json, sys
part, label, mode, d, mesh = sys.argv[1:6]
with open(mesh, "rb") as f:
    vertices = next(int(line.split()[2]) for line in f if line.startswith(b"element vertex"))
r = json.load(open(f"{d}/{mode}.report.json"))["counts"]
e = json.load(open(f"{d}/{mode}.eval.json"))
wall, kb = open(f"{d}/{mode}.time").read().split()
work = r.get("working_mesh", {}).get("vertices", "—")
circle = f"{100 * e['circle_radius_err_max']:.2f} %" if e['circle_radius_err_max'] == e['circle_radius_err_max'] else "—"
print(f"| {part} | {label} | {vertices:,} | {mode} | {sum(r['timings_s'].values()):.2f} | {float(wall):.2f} | "
      f"{int(kb) // 1024} | {work} | {e['primitive_recall']:.3f} | {e['line_f1']:.3f} | "
      f"{circle} | {e['constraint_precision']:.3f} | {e['constraint_recall']:.3f} | "
      f"{r['patches']} / {r['lines']} / {r['constraints']} |")
PY
  done
}

echo "| part | σ/h or scan | vertices | mode | analysis (s) | command (s) | peak MB | working vertices | primitive recall | line F1 | circle radius err max | constraint P | constraint R | patches / lines / constraints |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for section in ${SECTIONS:-noisy smooth}; do
  case $section in
    noisy)
      for part in ${PARTS:-plate shaft bracket pocket}; do
        for sigma in ${SIGMAS:-0.1 0.2 0.3}; do
          dir=$out/${part}_d${divs[$part]}
          mesh=$dir/${part}_refined_s${sigma}0.ply
          [[ -s $mesh ]] || "$bin/s2c-bench-features" inputs --names "$part" --sigma "$sigma" --div "${divs[$part]}" \
            --out "$dir" >/dev/null
          measure "$part" "$sigma" "$mesh" "$dir"
        done
      done
      ;;
    smooth)
      seed=${SEED:-1}
      for scan in ${SCANS:-plate bracket pocket shaft shaft_laser}; do
        src=$here/fixtures/scans/$scan dir=$out/smooth_$scan
        if [[ $seed != 1 ]]; then
          src=$out/scans_seed$seed/$scan dir=$out/smooth_seed${seed}_$scan
          if [[ ! -s $src/stream.yaml ]]; then
            sensor=(--sensor depth --views 12)
            [[ $scan == *_laser ]] && sensor=(--sensor laser --views 6)
            "$bin/scan2cad" simulate "$here/fixtures/parts/${scan%_laser}.stl" --out "$src" "${sensor[@]}" --noise 0.05 \
              --seed "$seed" --quiet
          fi
        fi
        mkdir -p "$dir"
        if [[ ! -s $dir/repaired.ply ]]; then
          # shellcheck disable=SC2086
          "$bin/scan2cad" reconstruct "$src" -o "$dir/mesh.ply" -q ${RECON_ARGS:---depth 9 --simplify 0} \
            2>"$dir/reconstruct.log"
          "$bin/scan2cad" repair "$dir/mesh.ply" -o "$dir/repaired.ply" -q 2>"$dir/repair.log"
        fi
        measure "${scan%_laser}" "scan $scan" "$dir/repaired.ply" "$dir"
      done
      ;;
    *) echo "unknown section $section" >&2; exit 2 ;;
  esac
done
