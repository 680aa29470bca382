#!/bin/bash
# Alternated timing of scan2cad-features binaries on one mesh (bench/README.md, features speed).
#   bench/features_ab.sh ROUNDS MESH BINARY...
# Each round runs every binary once, in turn, under `perf stat -e task-clock`; PAUSE=S waits S
# seconds before each run (the VM's fresh-memory regime). Per binary it prints min and median of
# "steps" (the report's read + analyse + write, s), CPU (task-clock, s) and each step.
set -euo pipefail
if [ $# -lt 3 ]; then
  echo "usage: $0 ROUNDS MESH BINARY... (PAUSE=seconds before each run)" >&2
  exit 2
fi
rounds=$1 mesh=$2
shift 2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for _ in $(seq "$rounds"); do
  for bin in "$@"; do
    sleep "${PAUSE:-0}"
    perf stat -x, -e task-clock "$bin" "$mesh" -o "$work/f.json" -q --report "$work/r.json" 2>"$work/stat" >/dev/null
    cpu=$(grep task-clock "$work/stat" | cut -d, -f1)
    python3 - "$bin" "$cpu" "$work/r.json" >>"$work/runs" <<'PY'
import json, sys
t = json.load(open(sys.argv[3]))["timings_s"]
print(sys.argv[1], round(sum(t.values()), 3), round(float(sys.argv[2]) / 1000, 3),
      round(t["read"], 3), round(t["analyse"], 3), round(t["write"], 3))
PY
  done
done
cat "$work/runs"
python3 - "$work/runs" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    name, *values = line.split()
    runs[name].append([float(v) for v in values])
for name, rows in runs.items():
    columns = zip(*rows)
    print(name, " ".join(f"{label} min {min(c):.3f} med {statistics.median(c):.3f}"
                         for label, c in zip(["steps", "cpu", "read", "analyse", "write"], columns)))
PY
