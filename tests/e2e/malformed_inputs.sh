#!/usr/bin/env bash
# e2e (issue 8): every kind of malformed input, through the executable that reads it: exit 2 in
# under 10 s, a message naming the file, no output written, the input byte-identical afterwards.
set -uo pipefail
bin="$1"; src="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work/in"
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# expect_bad NAME INPUT OUTPUT COMMAND...: INPUT (or $NAMED) must be named in stderr, OUTPUT must not exist.
expect_bad() {
  local name="$1" input="$2" output="$3"; shift 3
  local before; before=$(find "$input" -type f -exec sha256sum {} + | sort | sha256sum)
  local t0=$SECONDS
  timeout 30 "$@" >"$work/stdout" 2>"$work/stderr"; local rc=$?
  local took=$((SECONDS - t0))
  [[ $rc == 2 ]] || fail "$name: exit $rc, expected 2 ($(head -c 300 "$work/stderr"))"
  (( took < 10 )) || fail "$name: took ${took}s (limit 10 s)"
  local named="${NAMED:-$(basename "$input")}"   # what the message must name (default: the input file)
  grep -qF -- "$named" "$work/stderr" || fail "$name: message does not name $named: $(head -c 300 "$work/stderr")"
  [[ ! -e "$output" ]] || fail "$name: left $output"
  [[ $(find "$input" -type f -exec sha256sum {} + | sort | sha256sum) == "$before" ]] || fail "$name: input modified"
  echo "ok: $name ($(head -c 160 "$work/stderr" | tr '\n' ' '))"
}

in="$work/in"; out="$work/out.ply"
python3 - "$in" <<'PY'
import os, struct, sys
d = sys.argv[1]
def w(name, data):
    open(os.path.join(d, name), "wb").write(data if isinstance(data, bytes) else data.encode())
hdr = "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n" \
      "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
w("truncated.ply", (hdr % (3, 1)).encode() + struct.pack("<9f", *range(9)) + b"\x03\x00\x00")
w("absurd_count.ply", (hdr % (4000000000, 2000000000)).encode() + struct.pack("<9f", *range(9)))
w("absurd_count.stl", b"\0" * 80 + struct.pack("<I", 3000000000) + b"\0" * 50)
w("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n")
w("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")
w("garbage.stl", os.urandom(37))
w("empty.off", "")
w("bad.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 99999999999 float\n0 0 0\n")
pcd = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH %s\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %s\nDATA %s\n"
w("absurd_points.pcd", (pcd % (2000000000, 2000000000, "binary")).encode() + b"\0" * 12)
w("absurd_ascii.pcd", pcd % (900000000, 900000000, "ascii") + "1 2 3\n")
w("bad_type.pcd", (pcd % (1, 1, "ascii")).replace("TYPE F F F", "TYPE Q F F") + "1 2 3\n")
# A PNG whose header claims 100000 × 100000 16-bit pixels.
import zlib
def chunk(t, b): return struct.pack(">I", len(b)) + t + b + struct.pack(">I", zlib.crc32(t + b) & 0xffffffff)
w("huge.png", b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 100000, 100000, 16, 0, 0, 0, 0)) + chunk(b"IEND", b""))
w("deep.s2e", "param x = " + "(" * 100000 + "1" + ")" * 100000 + "\n")
w("syntax.s2e", "let h = select cylinder where radius ~\n")
w("good.s2e", "let h = select cylinder nearest [22, 12, 4]\nset h.radius = 3.5\n")
w("truncated.json", '{"format": "scan2cad.features/1", "patches": [')
PY

for f in truncated.ply absurd_count.ply absurd_count.stl bad_index.obj nan.off garbage.stl empty.off bad.vtk; do
  expect_bad "check $f" "$in/$f" "$out" "$bin/scan2cad" check "$in/$f"
  expect_bad "repair $f" "$in/$f" "$out" "$bin/scan2cad" repair "$in/$f" -o "$out"
  expect_bad "features $f" "$in/$f" "$work/f.json" "$bin/scan2cad" features "$in/$f" -o "$work/f.json"
done
for f in absurd_points.pcd absurd_ascii.pcd bad_type.pcd absurd_count.ply; do
  expect_bad "reconstruct $f" "$in/$f" "$out" "$bin/scan2cad" reconstruct "$in/$f" -o "$out"
done

# Streams: the bundled plate scan with one thing broken at a time.
stream_case() {  # NAME then a command run inside the copy
  local name="$1"; shift
  local s="$work/stream_$name"; rm -rf "$s"; cp -r "$src/fixtures/scans/plate" "$s"
  (cd "$s" && eval "$@")
  expect_bad "reconstruct stream: $name" "$s" "$out" "$bin/scan2cad" reconstruct "$s" -o "$out"
  expect_bad "acquire replay: $name" "$s" "$work/rec" "$bin/scan2cad" acquire --from "replay:$s" --out "$work/rec"
}
stream_case yaml_missing_width "sed -i '/^width:/d' stream.yaml"
stream_case index_bad_timestamp "printf '0.0 depth/000000.png\nabc depth/000001.png\n' > depth.txt"
stream_case index_escapes "printf '0.0 ../../etc/passwd\n' > depth.txt"
stream_case poses_bad_quaternion "printf '0.0 0 0 0 0 0 0 5\n' > poses.txt"
stream_case frame_huge_header "cp '$in/huge.png' depth/000003.png"
stream_case frame_truncated "head -c 100 depth/000002.png > t && mv t depth/000002.png"

# Features and scripts for the edit stage.
plate="$src/fixtures/parts/plate.stl"
"$bin/scan2cad" features "$plate" -o "$work/plate.json" --quiet || fail "features of the plate"
expect_bad "edit with truncated features.json" "$in/truncated.json" "$out" \
  "$bin/scan2cad" edit "$plate" --features "$in/truncated.json" --script "$in/good.s2e" -o "$out"
expect_bad "edit with a syntax error" "$in/syntax.s2e" "$out" \
  "$bin/scan2cad" edit "$plate" --features "$work/plate.json" --script "$in/syntax.s2e" -o "$out"
expect_bad "edit with 100000 nested parentheses" "$in/deep.s2e" "$out" \
  "$bin/scan2cad" edit "$plate" --features "$work/plate.json" --script "$in/deep.s2e" -o "$out"
# A grid that would not fit: refused up front, not an out-of-memory kill.
NAMED="--max-memory" expect_bad "repair with a grid beyond --max-memory" "$plate" "$out" \
  "$bin/scan2cad" repair "$plate" -o "$out" --strategy volumetric --voxel 0.0005 --max-memory 1

(( failures == 0 )) || { echo "$failures failure(s)" >&2; exit 1; }
echo "all malformed inputs refused cleanly"
