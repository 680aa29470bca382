#!/usr/bin/env bash
# Issue 3 benchmark: reconstruct accuracy, speed and memory, ours against Open3D, same inputs.
#
#   bench/run_reconstruct.sh [BUILD_DIR]        (default build/; run from anywhere)
#
# For each fixture part (the committed scans fixtures/scans/NAME: 12 depth views 640×480 taken
# alternately from above and below, σ = 0.05 mm, seed 1):
#   ours    build/bin/scan2cad reconstruct fixtures/scans/NAME -o OUT/NAME.ours.ply --cloud-out … --report …
#   Open3D  bench/peers/open3d_reconstruct.py fixtures/scans/NAME OUT/NAME.open3d.ply
#           (screened Poisson depth 9, 5 % density trim; skipped with a row saying so when
#           Open3D is not installed)
# both timed by /usr/bin/time (wall s, peak RSS), both measured by s2c-bench-accuracy against
# fixtures/parts/NAME.stl. Prints markdown tables on stdout; keeps every output in OUT.
#
# Environment: PARTS="plate shaft bracket pocket", OUT=DIR (default: a new /tmp directory),
# PYTHON=/usr/bin/python3 (Debian's, which sees python3-open3d), SAMPLES=200000,
# THRESHOLD=0.25, O3D_DEPTH=9, RECON_ARGS="" (extra arguments for scan2cad reconstruct),
# BUNNY_ARGS="" (arguments for build/bin/s2c-bench-bunny, run when it exists).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
build="${1:-build}"
bin="$build/bin"
parts="${PARTS:-plate shaft bracket pocket}"
out="${OUT:-$(mktemp -d /tmp/s2c-bench-reconstruct.XXXXXX)}"
py="${PYTHON:-/usr/bin/python3}"
samples="${SAMPLES:-200000}"
threshold="${THRESHOLD:-0.25}"
o3d_depth="${O3D_DEPTH:-9}"
mkdir -p "$out"

for exe in scan2cad scan2cad-reconstruct s2c-bench-accuracy; do
  if [[ ! -x "$bin/$exe" ]]; then
    echo "run_reconstruct.sh: $bin/$exe missing; build it: ninja -C $build scan2cad scan2cad-reconstruct s2c-bench-accuracy" >&2
    exit 2
  fi
done
if [[ ! -x /usr/bin/time ]]; then
  echo "run_reconstruct.sh: /usr/bin/time missing (apt-get install time)" >&2
  exit 2
fi
have_o3d=0
if [[ -x "$py" ]] && "$py" -c 'import open3d, cv2' 2>/dev/null; then have_o3d=1; fi

echo "outputs in $out" >&2
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
for p in $parts; do
  scan="fixtures/scans/$p"
  truth="fixtures/parts/$p.stl"
  echo "[$p] ours" >&2
  # shellcheck disable=SC2086
  /usr/bin/time -f "%e %M" -o "$out/$p.ours.time" \
    "$bin/scan2cad" reconstruct "$scan" -o "$out/$p.ours.ply" --cloud-out "$out/$p.ours.cloud.ply" --report "$out/$p.ours.report.json" --quiet ${RECON_ARGS:-} \
    2>"$out/$p.ours.log"
  echo $? >"$out/$p.ours.rc"
  if [[ "$(cat "$out/$p.ours.rc")" == 0 ]]; then
    "$bin/s2c-bench-accuracy" "$out/$p.ours.ply" "$truth" --samples "$samples" --threshold "$threshold" \
      --cloud "$out/$p.ours.cloud.ply" --dump "$out/$p.ours.far.ply" >"$out/$p.ours.acc.json" 2>>"$out/$p.ours.log"
  fi
  if [[ $have_o3d == 1 ]]; then
    echo "[$p] Open3D" >&2
    /usr/bin/time -f "%e %M" -o "$out/$p.open3d.time" \
      "$py" bench/peers/open3d_reconstruct.py "$scan" "$out/$p.open3d.ply" --depth "$o3d_depth" \
      >"$out/$p.open3d.report.json" 2>"$out/$p.open3d.log"
    echo $? >"$out/$p.open3d.rc"
    if [[ "$(cat "$out/$p.open3d.rc")" == 0 ]]; then
      "$bin/s2c-bench-accuracy" "$out/$p.open3d.ply" "$truth" --samples "$samples" --threshold "$threshold" \
        --dump "$out/$p.open3d.far.ply" >"$out/$p.open3d.acc.json" 2>>"$out/$p.open3d.log"
    fi
  fi
done

load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
echo "$(nproc) cores; load average before: $load_before, after: $load_after (timings are wall seconds; other load inflates them)"
echo
# Tables (python3 from the standard library only).
OUT_DIR="$out" PARTS_LIST="$parts" HAVE_O3D="$have_o3d" THRESHOLD="$threshold" python3 - <<'PY'
import json, os
out, parts, have_o3d = os.environ["OUT_DIR"], os.environ["PARTS_LIST"].split(), os.environ["HAVE_O3D"] == "1"
thr = os.environ["THRESHOLD"]

def load(path):
    try:
        with open(path) as f:
            text = f.read().strip()
        try:
            return json.loads(text)
        except ValueError:
            return json.loads(text.splitlines()[-1])
    except Exception:
        return None

def fmt(x, spec):
    return "—" if x is None else format(x, spec)

rows, details, targets, results = [], [], [], {}
for p in parts:
    for m, label in (("ours", "ours"), ("open3d", "Open3D")):
        if m == "open3d" and not have_o3d:
            rows.append(f"| {p} | Open3D | Open3D not installed | | | | | | | | |")
            continue
        try:
            rc = int(open(f"{out}/{p}.{m}.rc").read())
        except Exception:
            rc = -1
        if rc != 0:
            rows.append(f"| {p} | {label} | failed (exit {rc}; see {out}/{p}.{m}.log) | | | | | | | | |")
            continue
        secs, kb = (float(v) for v in open(f"{out}/{p}.{m}.time").read().split()[-2:])
        rep = load(f"{out}/{p}.{m}.report.json") or {}
        acc = load(f"{out}/{p}.{m}.acc.json")
        steps = rep.get("timings_s") if m == "ours" else rep.get("seconds")
        steps = " ".join(f"{k} {v:.1f}" for k, v in (steps or {}).items()) or "—"
        if m == "ours":
            c = rep.get("counts", {})
            pts_in, fused = c.get("points_in"), c.get("points_fused")
            depth, faces = rep.get("parameters", {}).get("poisson_depth"), c.get("faces")
        else:
            pts_in, fused, depth, faces = rep.get("points_in"), rep.get("points_fused"), rep.get("poisson_depth"), rep.get("faces")
        mb = kb / 1024.0
        r = dict(secs=secs, mb=mb, pts_in=pts_in, fused=fused, acc=acc,
                 pps=pts_in / secs if pts_in and secs > 0 else None,
                 mb_per_m=mb / (fused / 1e6) if fused else None)
        results[(p, m)] = r
        a = acc or {}
        rows.append(f"| {p} | {label} | {fmt(pts_in, ',')} | {secs:.2f} | {fmt(r['pps'], ',.0f')} | {mb:.0f} | "
                    f"{fmt(r['mb_per_m'], '.0f')} | {fmt(a.get('mean_recon_to_true_mm'), '.4f')} | "
                    f"{fmt(a.get('coverage'), '.4f')} | {fmt(a.get('chamfer_mm'), '.4f')} | {fmt(a.get('hausdorff_mm'), '.3f')} |")
        e = a.get("sharp_edges", {})
        details.append(f"| {p} | {label} | {fmt(fused, ',')} | {fmt(depth, 'd')} | {fmt(faces, ',')} | "
                       f"{fmt(a.get('p95_recon_to_true_mm'), '.4f')} | {fmt(a.get('max_recon_to_true_mm'), '.3f')} | "
                       f"{fmt(a.get('mean_true_to_recon_mm'), '.4f')} | "
                       f"{fmt(e.get('mean_recon_to_true_near_mm'), '.4f')} / {fmt(e.get('mean_recon_to_true_far_mm'), '.4f')} | "
                       f"{fmt(e.get('coverage_near'), '.4f')} / {fmt(e.get('coverage_far'), '.4f')} | "
                       f"{fmt(e.get('uncovered_share_near'), '.2f')} | {fmt(a.get('cloud_coverage'), '.4f')} | {steps} |")
        if m == "ours" and acc:
            ok = lambda b: "yes" if b else "**no**"
            targets.append(f"| {p} | {ok(acc['mean_recon_to_true_mm'] <= 0.023)} | {ok(acc['coverage'] >= 0.97)} | "
                           f"{ok(r['pps'] is not None and r['pps'] >= 250000)} | {ok(r['mb_per_m'] is not None and r['mb_per_m'] <= 1024)} |")
    o, q = results.get((p, "ours")), results.get((p, "open3d"))
    if o and q:
        me_o = (o["acc"] or {}).get("mean_recon_to_true_mm")
        me_q = (q["acc"] or {}).get("mean_recon_to_true_mm")
        ratio_err = f"{me_o / me_q:.2f}×" if me_o is not None and me_q else "—"
        rows.append(f"| {p} | *ours/Open3D* | | *{o['secs'] / q['secs']:.2f}×* | | *{o['mb'] / q['mb']:.2f}×* | | "
                    f"*{ratio_err}* | | | |")

print(f"| part | method | input points | seconds | points/s | peak MB | MB per M fused | mean recon→true (mm) | coverage@{thr} | chamfer (mm) | hausdorff (mm) |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
print()
print("| part | method | fused points | Poisson depth | faces | p95 recon→true | max recon→true | mean true→recon | mean recon→true near / far from sharp edges | coverage near / far | uncovered share near edges | cloud coverage | steps (s) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
print("\n".join(details))
print()
print("Issue 3 targets (ours): mean recon→true ≤ 0.023 mm · coverage ≥ 0.97 · ≥ 250k input points/s · ≤ 1 GB per M fused points")
print()
print("| part | mean ≤ 0.023 | coverage ≥ 0.97 | ≥ 250k pts/s | ≤ 1 GB / M fused |")
print("|---|---|---|---|---|")
print("\n".join(targets))
PY

if [[ -x "$bin/s2c-bench-bunny" ]]; then
  echo
  echo "Bunny registration (\`$bin/s2c-bench-bunny ${BUNNY_ARGS:-}\`):"
  echo
  echo '```'
  # shellcheck disable=SC2086
  "$bin/s2c-bench-bunny" ${BUNNY_ARGS:-} >"$out/bunny.json" 2>"$out/bunny.log"
  rc=$?
  # One line per view when the output is JSON (jq present), else as printed.
  if command -v jq >/dev/null && jq -e . "$out/bunny.json" >/dev/null 2>&1; then
    jq -c 'if type == "object" then del(.views) else . end' "$out/bunny.json"
    jq -c '.views[]?' "$out/bunny.json"
  else
    cat "$out/bunny.json"
  fi
  [[ $rc == 0 ]] || { echo "s2c-bench-bunny exited $rc:"; tail -5 "$out/bunny.log"; }
  echo '```'
fi
exit 0
