#!/usr/bin/env bash
# Issue 4 benchmarks of the repair stage; prints Markdown tables on stdout, keeps every output in OUT.
#
#   bench/run_repair.sh [BUILD_DIR]        (default build/; run from anywhere)
#
# Sections (SECTIONS="defects wrap vdf", default all three):
#   defects  s2c-make-defects fixtures/parts/NAME.stl --seed SEED → 8 defective variants per part;
#            scan2cad repair on each (default options) → scan2cad check (cad_ready), report
#            counts.path, s2c-bench-accuracy against fixtures/parts/NAME.stl (Chamfer, Hausdorff),
#            repair time (the report's "repair" step) and wall time / peak RSS of the process; also
#            the defective input's own distances to the part (what the defect moved: a repair that
#            keeps every input triangle cannot get below them).
#   wrap     CGAL 5.5 alpha_wrap_3 (s2c-bench-alpha-wrap, alpha = diag/200, offset = diag/2000) on
#            each WRAP_INPUTS mesh, then scan2cad repair --strategy volumetric --resolution N for N in
#            WRAP_RES (ascending; stops at the first N whose Hausdorff to the input is ≤ CGAL's): the
#            matched-Hausdorff time ratio; once per WRAP_EXTRACT (default "mc dc"), with --decimate
#            WRAP_DECIMATE (default 0.25, the repair's default; 0 = the extracted mesh as it is).
#            Skipped when s2c-bench-alpha-wrap was not built (no CGAL).
#   vdf      s2c-bench-vdf step; s2c-bench-vdf cad VDF_INPUTS --div 256 --band 3;
#            s2c-bench-vdf memory MESH --div 1024 for each MEMORY_INPUTS (each alone: nothing else runs meanwhile).
#
# Environment: PARTS="plate shaft bracket pocket", SEED=1, OUT=DIR (default: a new /tmp directory),
# SAMPLES=200000 (per surface, for the distances), WRAP_INPUTS (default: the four fixture parts and
# the CGAL fandisk), WRAP_RES="192 320 448 640 896", WRAP_EXTRACT="mc dc", WRAP_DECIMATE=0.25, VDF_INPUTS (default: the fixture parts, cgal_fandisk,
# cgal_part, abc_*), MEMORY_INPUTS (default: bracket.stl and abc_00000009, the widest band at
# --div 256), REAL=../shared/data/real/cad.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root" || exit 2
build="${1:-build}"
bin="$build/bin"
out="${OUT:-$(mktemp -d /tmp/s2c-bench-repair.XXXXXX)}"
real="${REAL:-$root/../shared/data/real/cad}"
mkdir -p "$out"

for exe in scan2cad scan2cad-repair scan2cad-check s2c-make-defects s2c-bench-accuracy s2c-bench-vdf; do
  if [[ ! -x "$bin/$exe" ]]; then
    echo "run_repair.sh: $bin/$exe missing; build it: ninja -C $build scan2cad scan2cad-repair scan2cad-check s2c-make-defects s2c-bench-accuracy s2c-bench-vdf [s2c-bench-alpha-wrap]" >&2
    exit 2
  fi
done

echo "outputs in $out" >&2
echo "$(nproc) cores; load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo

BIN="$bin" OUT_DIR="$out" REAL_DIR="$real" python3 - <<'PY'
import glob, json, os, subprocess, sys, time

bin_, out, real = os.environ["BIN"], os.environ["OUT_DIR"], os.environ["REAL_DIR"]
parts = os.environ.get("PARTS", "plate shaft bracket pocket").split()
seed = os.environ.get("SEED", "1")
samples = os.environ.get("SAMPLES", "200000")
sections = os.environ.get("SECTIONS", "defects wrap vdf").split()
variants = ["holes", "nested", "flipped", "duplicates", "gap", "self_intersections", "loose", "everything"]


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run(cmd, stdout_path=None, log_path=None):
    """Runs cmd; returns (exit code, wall s, peak RSS MB) of that process alone (wait4)."""
    t0 = time.monotonic()
    with open(stdout_path or os.devnull, "w") as so, open(log_path or os.devnull, "a") as se:
        p = subprocess.Popen(cmd, stdout=so, stderr=se)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    return os.waitstatus_to_exitcode(status), wall, ru.ru_maxrss / 1024.0


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


def accuracy(mesh, truth, tag):
    path = f"{out}/{tag}.acc.json"
    run([f"{bin_}/s2c-bench-accuracy", mesh, truth, "--samples", samples], path, f"{out}/{tag}.log")
    return load(path) or {}


def check(mesh, tag):
    path = f"{out}/{tag}.check.json"
    run([f"{bin_}/scan2cad", "check", mesh], path, f"{out}/{tag}.log")
    return load(path) or {}


# ---------------------------------------------------------------- defects
if "defects" in sections:
    rows, summary = [], []
    for p in parts:
        truth = f"fixtures/parts/{p}.stl"
        ddir = f"{out}/defects_{p}"
        log(f"[defects] {p}: s2c-make-defects")
        rc, _, _ = run([f"{bin_}/s2c-make-defects", truth, "--out", ddir, "--seed", seed, "--quiet"], None, f"{out}/defects_{p}.log")
        meta = load(f"{ddir}/defects.json") or {}
        by_name = {v["name"]: v for v in meta.get("variants", [])}
        ok = n = 0
        worst_ch = worst_h = 0.0
        for v in variants:
            tag = f"{p}.{v}"
            src, dst = f"{ddir}/{v}.ply", f"{out}/{tag}.repaired.ply"
            log(f"[defects] {p} {v}: repair")
            rc, wall, mb = run([f"{bin_}/scan2cad", "repair", src, "-o", dst, "--report", f"{out}/{tag}.report.json", "--quiet"],
                               None, f"{out}/{tag}.log")
            rep = load(f"{out}/{tag}.report.json") or {}
            counts = rep.get("counts", {})
            secs = (rep.get("timings_s") or {}).get("repair")
            info = by_name.get(v, {})
            defects = " ".join(f"{k} {val}" for k, val in (info.get("defects") or {}).items())
            n += 1
            if rc != 0:
                rows.append(f"| {p} | {v} | {defects} | {fmt(info.get('check', {}).get('faces'), ',')} | exit {rc} | **no** | "
                            f"{counts.get('path', '—')} | — | — | — | — | {fmt(secs, '.2f')} | {wall:.2f} | {mb:.0f} |")
                continue
            c = check(dst, tag)
            a = accuracy(dst, truth, tag)
            ai = accuracy(src, truth, f"{tag}.input")  # what the defect itself moved: the floor for geometry-only repair
            ready = bool(c.get("cad_ready"))
            ok += ready
            ch, h = a.get("chamfer_mm"), a.get("hausdorff_mm")
            if ch is not None:
                worst_ch, worst_h = max(worst_ch, ch), max(worst_h, h)
            rows.append(f"| {p} | {v} | {defects} | {fmt(info.get('check', {}).get('faces'), ',')} | 0 | "
                        f"{'yes' if ready else '**no**'} | {counts.get('path', '—')} | {fmt(c.get('faces'), ',')} | "
                        f"{fmt(ch, '.4f')}{'' if ch is None or ch <= 0.03 else ' ✗'} | {fmt(h, '.3f')} | "
                        f"{fmt(ai.get('chamfer_mm'), '.4f')} / {fmt(ai.get('hausdorff_mm'), '.3f')} | {fmt(secs, '.2f')} | {wall:.2f} | {mb:.0f} |")
        summary.append(f"| {p} | {fmt(meta.get('edge_mm'), '.2f')} | {fmt(meta.get('clean', {}).get('faces'), ',')} | {ok}/{n} | {worst_ch:.4f} | {worst_h:.3f} |")
    print(f"### Defective CAD parts (s2c-make-defects --seed {seed}) → scan2cad repair (defaults)")
    print()
    print("| part | variant | defects made | faces in | exit | CAD-ready | path | faces out | Chamfer mm | Hausdorff mm | input Chamfer / Hausdorff mm | repair s | wall s | peak MB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print()
    print("| part | refined edge mm | clean faces | CAD-ready | worst Chamfer mm (target ≤ 0.03) | worst Hausdorff mm |")
    print("|---|---|---|---|---|---|")
    print("\n".join(summary))
    print(flush=True)

# ---------------------------------------------------------------- wrap
if "wrap" in sections:
    if not os.access(f"{bin_}/s2c-bench-alpha-wrap", os.X_OK):
        print("### CGAL alpha wrap anchor: skipped (s2c-bench-alpha-wrap not built: CGAL not found)\n")
    else:
        default = [f"fixtures/parts/{p}.stl" for p in parts] + [f"{real}/cgal_fandisk.off"]
        inputs = os.environ.get("WRAP_INPUTS", " ".join(default)).split()
        res_list = [int(r) for r in os.environ.get("WRAP_RES", "192 320 448 640 896").split()]
        extracts = os.environ.get("WRAP_EXTRACT", "mc dc").split()
        decimate = os.environ.get("WRAP_DECIMATE", "0.25")
        rows = []
        for src in inputs:
            name = os.path.basename(src)
            tag = f"wrap.{name}"
            log(f"[wrap] {name}: CGAL alpha_wrap_3")
            rc, wall_c, mb_c = run([f"{bin_}/s2c-bench-alpha-wrap", src, f"{out}/{tag}.cgal.ply"], f"{out}/{tag}.cgal.json", f"{out}/{tag}.log")
            cg = load(f"{out}/{tag}.cgal.json") or {}
            if rc != 0 or not cg:
                rows.append(f"| {name} | CGAL alpha wrap | failed (exit {rc}) | | | | | | | | |")
                continue
            ca = accuracy(f"{out}/{tag}.cgal.ply", src, f"{tag}.cgal")
            cc = check(f"{out}/{tag}.cgal.ply", f"{tag}.cgal")
            h_c = ca.get("hausdorff_mm", 0)
            rows.append(f"| {name} | CGAL alpha wrap (α {cg['alpha_mm']:.3f}, offset {cg['offset_mm']:.4f}) | — | {cg['seconds']:.2f} | — | "
                        f"{wall_c:.2f} | {mb_c:.0f} | {fmt(cc.get('faces'), ',')} | {'yes' if cc.get('cad_ready') else 'no'} | "
                        f"{fmt(ca.get('chamfer_mm'), '.4f')} | {fmt(h_c, '.4f')} | |")
            for extract in extracts:
                matched = None
                for res in res_list:
                    log(f"[wrap] {name}: ours --extract {extract} --resolution {res}")
                    t = f"{tag}.ours.{extract}{res}"
                    rc, wall, mb = run([f"{bin_}/scan2cad", "repair", src, "-o", f"{out}/{t}.ply", "--strategy", "volumetric",
                                        "--extract", extract, "--resolution", str(res), "--decimate", decimate,
                                        "--report", f"{out}/{t}.report.json",
                                        "--quiet"], None, f"{out}/{t}.log")
                    rep = load(f"{out}/{t}.report.json") or {}
                    if rc != 0:
                        rows.append(f"| {name} | ours {extract} --resolution {res} | failed (exit {rc}) | | | | | | | | | |")
                        continue
                    vp = rep.get("counts", {}).get("volumetric_path", {})
                    vol = (vp.get("volumetric") or [{}])[-1]
                    core = sum(vol.get(k, 0) for k in ("seconds_field", "seconds_sign", "seconds_extract"))
                    secs = (rep.get("timings_s") or {}).get("repair")
                    a = accuracy(f"{out}/{t}.ply", src, t)
                    c = check(f"{out}/{t}.ply", t)
                    h = a.get("hausdorff_mm", 1e9)
                    hit = h <= h_c
                    steps = vp.get("seconds", {})
                    rows.append(f"| {name} | ours {extract} --resolution {res} (voxel {fmt(vp.get('voxel_mm'), '.4f')}) | {core:.2f} | "
                                f"{fmt(secs, '.2f')} (volumetric {fmt(steps.get('volumetric'), '.1f')}, decimate {fmt(steps.get('decimate'), '.1f')}) | "
                                f"{cg['seconds'] / secs:.2f}× | {wall:.2f} | {mb:.0f} | {fmt(c.get('faces'), ',')} | "
                                f"{'yes' if c.get('cad_ready') else 'no'} | {fmt(a.get('chamfer_mm'), '.4f')} | {h:.4f} | "
                                f"{'**matched**' if hit else ''} |")
                    if hit:
                        matched = (res, secs, core, wall)
                        break
                if matched:
                    res, secs, core, wall = matched
                    rows.append(f"| {name} | *CGAL ÷ ours {extract} at matched Hausdorff (res {res})* | *{cg['seconds'] / core:.1f}× (core)* | "
                                f"*{cg['seconds'] / secs:.2f}× (repair step)* | | *{wall_c / wall:.2f}× (wall)* | | | | | | |")
                else:
                    rows.append(f"| {name} | *ours {extract}: no resolution in {res_list} reached CGAL's Hausdorff* | | | | | | | | | | |")
        print(f"### Anchor: CGAL 5.5 alpha_wrap_3 (α = diag/200, offset = diag/2000) vs scan2cad repair --strategy volumetric --decimate {decimate}")
        print()
        print("Distances to the input mesh. `core s` = VDF field + sign + Marching Cubes (report `seconds_field/sign/extract`); "
              "`repair s` = the whole repair step (volumetric incl. its validation, decimation, final check); CGAL's `seconds` = "
              "alpha_wrap_3 alone; wall and peak RSS of the whole process (read, write included).")
        print()
        print("| mesh | method | core s | repair s / CGAL s | CGAL ÷ repair | wall s | peak MB | faces | CAD-ready | Chamfer mm | Hausdorff mm | |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        print("\n".join(rows))
        print(flush=True)

# ---------------------------------------------------------------- vdf
if "vdf" in sections:
    default = [f"fixtures/parts/{p}.stl" for p in parts] + [f"{real}/cgal_fandisk.off", f"{real}/cgal_part.off"] + \
        sorted(glob.glob(f"{real}/abc_*.stl"))
    inputs = os.environ.get("VDF_INPUTS", " ".join(default)).split()
    mem_default = f"fixtures/parts/bracket.stl {real}/abc_00000009_9b3d6a97e8de4aa193b81000_trimesh_001.stl"
    runs = [("step experiment", [f"{bin_}/s2c-bench-vdf", "step"], "vdf_step"),
            ("equal voxel vs OpenVDB", [f"{bin_}/s2c-bench-vdf", "cad", *inputs, "--div", "256", "--band", "3"], "vdf_cad")]
    for i, mem_in in enumerate(os.environ.get("MEMORY_INPUTS", mem_default).split()):
        runs.append((f"memory at 1024³ equivalent ({os.path.basename(mem_in)})",
                     [f"{bin_}/s2c-bench-vdf", "memory", mem_in, "--div", "1024"], f"vdf_memory{i}"))
    for title, cmd, tag in runs:
        log(f"[vdf] {title}")
        rc, wall, mb = run(cmd, f"{out}/{tag}.md", f"{out}/{tag}.log")
        shown = " ".join(c.replace(os.getcwd() + "/", "") for c in cmd)
        print(f"### s2c-bench-vdf: {title}\n\n`{shown}` (exit {rc}, {wall:.1f} s, peak RSS {mb:.0f} MB)\n")
        print(open(f"{out}/{tag}.md").read())
        sys.stdout.flush()
PY
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
