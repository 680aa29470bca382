#!/usr/bin/env bash
# e2e: `scan2cad run` killed with SIGKILL inside each of its stages (driver and stage at once),
# then re-run: the outputs must be byte-identical to an uninterrupted run, and at no point may
# the manifest vouch for a file whose bytes it does not hash.
set -euo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
outputs="stream mesh.ply cloud.ply repaired.ply features.json segments.ply check.json"

digest() {  # one line per output: its hash (a folder: the hash of its sorted file hashes)
  local dir="$1"
  for o in $outputs; do
    if [[ -d "$dir/$o" ]]; then (cd "$dir/$o" && find . -type f -exec sha256sum {} + | sort | sha256sum | cut -c1-64)
    elif [[ -f "$dir/$o" ]]; then sha256sum "$dir/$o" | cut -c1-64
    else echo missing; fi
  done
}

manifest_honest() {  # every output the manifest lists has the hash it records
  python3 - "$1" "$2" <<'PY'
import hashlib, json, os, sys
out, bin_dir = sys.argv[1], sys.argv[2]
path = os.path.join(out, "manifest.json")
if not os.path.exists(path):
    sys.exit(0)
m = json.load(open(path))  # written atomically: a torn manifest would not parse
def h(p):
    if os.path.isdir(p):
        lines = []
        for root, _, files in os.walk(p):
            for f in files:
                q = os.path.join(root, f)
                lines.append("%s\t%s" % (os.path.relpath(q, p), hashlib.sha256(open(q, "rb").read()).hexdigest()))
        return hashlib.sha256("".join(l + "\n" for l in sorted(lines)).encode()).hexdigest()
    return hashlib.sha256(open(p, "rb").read()).hexdigest()
for s in m["stages"]:
    if s.get("status") != "ok":
        continue
    for p, want in s.get("outputs", {}).items():
        if os.path.exists(p) and h(p) != want:
            sys.exit("manifest vouches for %s (stage %s) but its bytes differ" % (p, s["name"]))
PY
}

run() { "$bin/scan2cad" run --from "replay:$src/fixtures/scans/plate" --out "$1" --quiet; }

run "$work/ref" || fail "uninterrupted run exited $?"
digest "$work/ref" > "$work/ref.digest"
grep -q missing "$work/ref.digest" && fail "the uninterrupted run left an output missing"

# Kill points: STAGE:SECONDS, the kill lands that long after the stage's own process has started
# (so each stage is hit mid-run however fast or slow this build is: a sanitizer build is ~8×
# slower). Default: inside every stage that writes an output; S2C_CRASH_KILLS overrides (the
# sanitizer build's CTest entry passes fewer: each point costs a whole pipeline re-run there).
kills="${S2C_CRASH_KILLS:-acquire:0.1 reconstruct:1 repair:0.5 features:0.3 check:0.05 report:0.2}"

# Waits until the stage's executable runs in process group $1, then $3 seconds more; returns
# early (1) when the run has ended before that.
wait_for_stage() {
  local group="$1" stage="$2" delay="$3"
  until pgrep -g "$group" -f "/scan2cad-$stage"'( |$)' > /dev/null; do
    [[ "$(ps -o stat= -p "$group" 2>/dev/null)" == [^Z]* ]] || return 1  # ended (gone or a zombie)
    sleep 0.02
  done
  sleep "$delay"
}

i=0
for point in $kills; do
  stage="${point%%:*}"; delay="${point#*:}"
  i=$((i + 1)); out="$work/k$i"
  setsid "$bin/scan2cad" run --from "replay:$src/fixtures/scans/plate" --out "$out" --quiet &
  pid=$!
  wait_for_stage "$pid" "$stage" "$delay" || fail "the run ended before its $stage stage was seen"
  kill -KILL -- "-$pid" 2>/dev/null || true   # the whole process group: driver and stage
  wait "$pid" 2>/dev/null || true
  manifest_honest "$out" "$bin" || fail "after a kill in $stage"
  run "$out" || fail "re-run after a kill in $stage exited $?"
  manifest_honest "$out" "$bin" || fail "after the re-run (kill in $stage)"
  digest "$out" > "$out.digest"
  diff "$work/ref.digest" "$out.digest" > /dev/null || fail "outputs after a kill in $stage (+${delay}s) differ from the uninterrupted run"
  leftovers=$(find "$out" -name '.*.tmp-*' | wc -l)
  [[ $leftovers == 0 ]] || fail "$leftovers temporary file(s) left after the re-run (kill in $stage)"
  echo "kill in $stage (+${delay}s): re-run identical"
done
