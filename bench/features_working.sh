#!/bin/bash
# Large noisy meshes: the analysis on the working mesh (the default) against the whole mesh
# (--working-vertices 0), both against the fixture parts' truth (bench/README.md, "a working
# mesh for large noisy meshes").
#   bench/features_working.sh [BUILD_DIR]
# Environment: OUT (default /tmp/s2c-features-working), SIGMAS (default "0.1 0.2 0.3"), PARTS
# (default "plate shaft bracket pocket"), FULL=0 skips the whole-mesh runs (8-17 s each).
# Each part is refined to about a million vertices (DIVS below: the diagonal over the longest
# edge), then given Gaussian noise of σ mean edges (`s2c-bench-features inputs`, seed 1). Per
# mesh it prints one row per mode: vertices, the analysis' time (the report's steps from arrays
# to groups, s), the whole command's time and peak memory (/usr/bin/time), the working mesh's
# vertices, and the quality columns of `s2c-bench-features mesh`.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "${1:-$here/build}" && pwd)/bin
out=${OUT:-/tmp/s2c-features-working}
mkdir -p "$out"
declare -A divs=([plate]=560 [shaft]=620 [bracket]=510 [pocket]=480)
echo "| part | σ/h | vertices | mode | analysis (s) | command (s) | peak MB | working vertices | primitive recall | line F1 | circle radius err max | constraint P | constraint R | patches / lines / constraints |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for part in ${PARTS:-plate shaft bracket pocket}; do
  for sigma in ${SIGMAS:-0.1 0.2 0.3}; do
    dir=$out/${part}_d${divs[$part]}
    mesh=$dir/${part}_refined_s${sigma}0.ply
    [[ -s $mesh ]] || "$bin/s2c-bench-features" inputs --names "$part" --sigma "$sigma" --div "${divs[$part]}" \
      --out "$dir" >/dev/null
    modes="working"
    [[ ${FULL:-1} == 0 ]] || modes="working full"
    for mode in $modes; do
      wv=()
      [[ $mode == full ]] && wv=(--working-vertices 0)
      /usr/bin/time -f "%e %M" -o "$dir/$mode.time" "$bin/scan2cad-features" "$mesh" -o "$dir/$mode.json" \
        --report "$dir/$mode.report.json" -q "${wv[@]}"
      "$bin/s2c-bench-features" mesh "$mesh" "$here/fixtures/parts/$part.truth.json" --features "$dir/$mode.json" \
        --json "$dir/$mode.eval.json" >/dev/null
      python3 - "$part" "$sigma" "$mode" "$dir" "$mesh" <<'PY'
import json, sys
part, sigma, mode, d, mesh = sys.argv[1:6]
with open(mesh, "rb") as f:
    vertices = next(int(line.split()[2]) for line in f if line.startswith(b"element vertex"))
r = json.load(open(f"{d}/{mode}.report.json"))["counts"]
e = json.load(open(f"{d}/{mode}.eval.json"))
wall, kb = open(f"{d}/{mode}.time").read().split()
work = r.get("working_mesh", {}).get("vertices", "—")
print(f"| {part} | {sigma} | {vertices:,} | {mode} | {sum(r['timings_s'].values()):.2f} | {float(wall):.2f} | "
      f"{int(kb) // 1024} | {work} | {e['primitive_recall']:.3f} | {e['line_f1']:.3f} | "
      f"{100 * e['circle_radius_err_max']:.2f} % | {e['constraint_precision']:.3f} | {e['constraint_recall']:.3f} | "
      f"{r['patches']} / {r['lines']} / {r['constraints']} |")
PY
    done
  done
done
