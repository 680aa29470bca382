#!/usr/bin/env python3
"""Writes the seed corpora fuzz/corpus/TARGET/ from the fixtures (run from anywhere; needs the
built `scan2cad` for the features.json seed: BIN=build/bin). The seeds are committed; re-run this
when a format changes."""
import os, shutil, struct, subprocess, sys, zlib

here = os.path.dirname(os.path.abspath(__file__))
src = os.path.dirname(here)
bin_dir = os.environ.get("BIN", os.path.join(src, "build", "bin"))
corpus = os.path.join(here, "corpus")


def put(target, name, data):
    d = os.path.join(corpus, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def png16(w, h, values):
    raw = b"".join(b"\0" + b"".join(struct.pack(">H", values[y * w + x]) for x in range(w)) for y in range(h))
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# --- mesh: first byte picks .ply .stl .obj .off .vtk (0..4) --------------------------------------
tetra_v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
tetra_f = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
ply_ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n" \
            "element face 4\nproperty list uchar int vertex_indices\nend_header\n" + \
            "".join("%g %g %g\n" % v for v in tetra_v) + "".join("3 %d %d %d\n" % f for f in tetra_f)
put("mesh", "tetra_ascii.ply", b"\x00" + ply_ascii.encode())
ply_bin = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
           "property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n").encode()
ply_bin += b"".join(struct.pack("<3d", *v) for v in tetra_v) + b"".join(struct.pack("<B3i", 3, *f) for f in tetra_f)
put("mesh", "tetra_binary.ply", b"\x00" + ply_bin)
# Big-endian, with normals, a list before the coordinates, an element between the vertices and
# the faces and a list after the corners: the layouts core/src/io/binary_ply.cpp walks.
ply_be = ("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty list uchar float w\nproperty float x\n"
          "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
          "element edge 1\nproperty int vertex1\nproperty int vertex2\nelement face 4\n"
          "property list ushort uint vertex_index\nproperty list uchar float texcoord\nend_header\n").encode()
ply_be += b"".join(struct.pack(">Bf", 1, 0.5) + struct.pack(">6f", *v, 0, 0, 1) for v in tetra_v)
ply_be += struct.pack(">2i", 0, 1) + b"".join(struct.pack(">H3IB2f", 3, *f, 2, 0.25, 0.75) for f in tetra_f)
put("mesh", "tetra_big_endian.ply", b"\x00" + ply_be)
stl_ascii = "solid t\n" + "".join("facet normal 0 0 0\nouter loop\n" + "".join("vertex %g %g %g\n" % tetra_v[i] for i in f)
                                  + "endloop\nendfacet\n" for f in tetra_f) + "endsolid t\n"
put("mesh", "tetra_ascii.stl", b"\x01" + stl_ascii.encode())
stl_bin = b"\0" * 80 + struct.pack("<I", 4) + b"".join(
    struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *tetra_v[i]) for i in f) + b"\0\0" for f in tetra_f)
put("mesh", "tetra_binary.stl", b"\x01" + stl_bin)
obj = "".join("v %g %g %g\n" % v for v in tetra_v) + "".join("f %d %d %d\n" % (f[0] + 1, f[1] + 1, f[2] + 1) for f in tetra_f)
put("mesh", "tetra.obj", b"\x02" + obj.encode())
put("mesh", "quad.obj", b"\x02v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n")
off = "OFF\n4 4 0\n" + "".join("%g %g %g\n" % v for v in tetra_v) + "".join("3 %d %d %d\n" % f for f in tetra_f)
put("mesh", "tetra.off", b"\x03" + off.encode())
vtk = ("# vtk DataFile Version 3.0\ntetra\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n" +
       "".join("%g %g %g\n" % v for v in tetra_v) + "POLYGONS 4 16\n" + "".join("3 %d %d %d\n" % f for f in tetra_f))
put("mesh", "tetra.vtk", b"\x04" + vtk.encode())

# --- pcd ----------------------------------------------------------------------------------------
head = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 12\nHEIGHT 1\n" \
       "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 12\nDATA %s\n"
pts = [(0.1 * i, 0.05 * i * i, 1 + 0.01 * i) for i in range(12)]
put("pcd", "ascii.pcd", head % "ascii" + "".join("%g %g %g\n" % p for p in pts))
put("pcd", "binary.pcd", (head % "binary").encode() + b"".join(struct.pack("<3f", *p) for p in pts))
put("pcd", "organized_nan.pcd", ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                                 "WIDTH 4\nHEIGHT 3\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 12\nDATA ascii\n") +
    "".join(("nan nan nan 0\n" if i % 5 == 0 else "%g %g %g 4.2e6\n" % pts[i]) for i in range(12)))

# --- stream: stream.yaml, depth.txt, poses.txt, a frame, separated by "\n%%\n" -------------------
plate = os.path.join(src, "fixtures", "scans", "plate")
yaml = open(os.path.join(plate, "stream.yaml")).read()
yaml4 = yaml.replace("width: 640", "width: 4").replace("height: 480", "height: 4")
frame = png16(4, 4, [0, 1000, 2000, 3000] * 4)
index = "# t f\n0.0 depth/000000.png\n"
poses = "0.0 1 2 3 0 0 0 1\n"
put("stream", "depth4x4", (yaml4 + "\n%%\n" + index + "\n%%\n" + poses + "\n%%\n").encode() + frame)
put("stream", "plate_index", yaml + "\n%%\n" + open(os.path.join(plate, "depth.txt")).read() + "\n%%\n" +
    open(os.path.join(plate, "poses.txt")).read())
laser = os.path.join(src, "fixtures", "scans", "shaft_laser")
lyaml = open(os.path.join(laser, "stream.yaml")).read()
import re
lyaml4 = re.sub(r"width: \d+", "width: 4", re.sub(r"height: \d+", "height: 4", lyaml))
put("stream", "laser4x4", (lyaml4 + "\n%%\n" + index + "\n%%\n\n%%\n").encode() + frame)

# --- features.json ------------------------------------------------------------------------------
exe = os.path.join(bin_dir, "scan2cad")
if os.path.exists(exe):
    out = os.path.join(corpus, "features_json")
    os.makedirs(out, exist_ok=True)
    for part in ["plate", "shaft"]:
        subprocess.run([exe, "features", os.path.join(src, "fixtures", "parts", part + ".stl"), "-o",
                        os.path.join(out, part + ".json"), "--quiet"], check=True)
else:
    print("no %s: features_json seeds not regenerated" % exe, file=sys.stderr)

# --- edit scripts ---------------------------------------------------------------------------------
os.makedirs(os.path.join(corpus, "edit_script"), exist_ok=True)
for f in os.listdir(os.path.join(src, "fixtures", "edits")):
    if f.endswith(".s2e"):
        shutil.copy(os.path.join(src, "fixtures", "edits", f), os.path.join(corpus, "edit_script", f))
put("edit_script", "expressions.s2e", "param w = 2 * (3 + 4) mm\nlet h = select cylinder where radius ~ 3 +- 0.1 and not "
    "(normal parallel [0, 0, 1])\nlet t = select plane highest\nassert h.count == 5\nmove t by [0, 0, w / 14]\n"
    "constrain parallel(t, t)\nlock h\nset h.radius = h.radius + 0.1\n")

# --- usb profile packets ------------------------------------------------------------------------------
def packet(seq, n, flags=0, scale=0.01):
    h = struct.pack("<IHHIQHHfff", 0x4C433253, 1, 36, seq, 1000 * seq, n, flags, scale, -20.0, 0.0)
    return h + b"".join(struct.pack("<hHBB", i * 10 - 100, 10000 + i, 200, 0) for i in range(n))
put("usb_profile", "p0", packet(0, 16))
put("usb_profile", "p1_end", packet(1, 40, 1))
put("usb_profile", "empty", packet(7, 0))
print("seeds written to", corpus)
