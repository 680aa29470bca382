#!/usr/bin/env bash
# One command from a fresh Debian bookworm machine to a working scan2cad:
#   ./setup.sh demo   install what is missing, build, run the pipeline (with an edit) on a bundled scan → out/
#   ./setup.sh test   install what is missing, build, run the whole test suite (ctest)
# Safe to re-run: installs only what is missing, builds incrementally (Ninja + ccache).
set -euo pipefail
cd "$(dirname "$0")"
mode="${1:-demo}"
build="${S2C_BUILD_DIR:-build}"

case "$mode" in
  demo|test) ;;
  *) echo "usage: ./setup.sh demo|test" >&2; exit 2 ;;
esac

scripts/install-deps.sh
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release ${S2C_CMAKE_ARGS:-}
cmake --build "$build" -j "$(nproc)"

if [[ "$mode" == demo ]]; then
  "$build/bin/scan2cad" run fixtures/scans/plate --out out --edit fixtures/edits/plate_widen_holes.s2e
  echo
  echo "Done. Results in out/: cloud.ply, mesh.ply, repaired.ply (CAD-ready mesh), features.json and segments.ply (features),"
  echo "edited.ply and edited.features.json (corner holes widened to 7 mm by fixtures/edits/plate_widen_holes.s2e),"
  echo "check.json (is the final mesh CAD-ready?), manifest.json, reports/ (per-stage reports),"
  echo "report.html + report_files/ (pictures of every stage and the tables: open it in a browser)"
else
  ctest --test-dir "$build" --output-on-failure -j 2 --timeout 900
fi
