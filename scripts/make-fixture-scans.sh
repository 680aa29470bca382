#!/usr/bin/env bash
# Re-records the bundled scans in fixtures/scans/ from the fixture parts with the virtual scanner.
# Deterministic: the same build and seeds give the same bytes.
#   scripts/make-fixture-scans.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build}/bin"
for part in plate shaft bracket pocket; do
  "$bin/scan2cad" simulate "fixtures/parts/$part.stl" --out "fixtures/scans/$part" \
    --sensor depth --views 12 --noise 0.05 --seed 1 --quiet
done
"$bin/scan2cad" simulate fixtures/parts/shaft.stl --out fixtures/scans/shaft_laser \
  --sensor laser --views 6 --noise 0.05 --seed 1 --quiet
du -sh fixtures/scans/*
