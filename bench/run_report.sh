#!/usr/bin/env bash
# Issue 9 benchmark: how long pictures and the report take; prints a Markdown table on stdout.
# Builds nothing.
#
#   bench/run_report.sh [BUILD_DIR]        (default build/; run from anywhere)
#
# Needs hyperfine (scripts/install-deps.sh --bench) and BUILD_DIR/bin/scan2cad with its stages.
# Makes (or reuses) OUT/plate: scan2cad run on fixtures/scans/plate with the widen-holes edit and
# the true plate as reference; then times scan2cad render on its meshes and cloud and on a real
# mesh (the Stanford bunny zipper scan), and the report stage alone. Environment: OUT=DIR.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
build="${1:-build}"
bin="$build/bin"
out="${OUT:-$(mktemp -d /tmp/s2c-bench-report.XXXXXX)}"
mkdir -p "$out"
command -v hyperfine > /dev/null || { echo "hyperfine missing: scripts/install-deps.sh --bench" >&2; exit 2; }
ref=fixtures/parts/plate.stl
bunny=../shared/data/real/defective/stanford_bun_zipper.ply
[[ -s "$out/plate/report.html" ]] || "$bin/scan2cad" run fixtures/scans/plate --out "$out/plate" --reference "$ref" \
  --edit fixtures/edits/plate_widen_holes.s2e --quiet 2> /dev/null
echo "<!-- bench/run_report.sh at $(git rev-parse --short HEAD 2>/dev/null), $(date -u +%F), $(nproc) cores; outputs in $out -->"
faces() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['counts']['faces'])" "$1"; }
"$bin/scan2cad" render "$out/plate/repaired.ply" -o "$out/x.png" --report "$out/r.json" -q
echo "<!-- repaired plate: $(faces "$out/r.json") faces; cloud: $(grep -a -m1 'element vertex' "$out/plate/cloud.ply") -->"
hyperfine -N -w 1 -r 5 --export-markdown "$out/table.md" \
  -n "render repaired plate 1024×768" "$bin/scan2cad-render $out/plate/repaired.ply -o $out/a.png" \
  -n "render fused cloud 1024×768" "$bin/scan2cad-render $out/plate/cloud.ply -o $out/b.png" \
  -n "render features (patches + lines)" "$bin/scan2cad-render $out/plate/repaired.ply --features $out/plate/features.json -o $out/c.png" \
  -n "render deviation vs plate.stl" "$bin/scan2cad-render $out/plate/edited.ply --reference $ref -o $out/d.png" \
  -n "render bunny zipper (real)" "$bin/scan2cad-render $bunny -o $out/e.png" \
  -n "report stage (12 pictures 640×480 + tables)" "$bin/scan2cad-report $out/plate -o $out/report.html --reference $ref -q" \
  > /dev/null
cat "$out/table.md"
