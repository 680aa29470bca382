#!/usr/bin/env python3
"""Where a mesh's own surface lies, near a part's z axis: so that a feature's error can be told
apart from the error of the surface it was fitted to (bench/README.md, features, "a seventh, and
lines as precise as the working edge").

  bench/mesh_probe.py radius MESH ZMIN ZMAX RMIN RMAX
      median distance from the z axis of the vertices with ZMIN < z < ZMAX and RMIN < r < RMAX
      (a hole's or a counterbore's wall)
  bench/mesh_probe.py height MESH ZMIN ZMAX RMAX
      median z of the vertices with ZMIN < z < ZMAX within RMAX of the z axis (an end face)

MESH is a PLY (binary little endian or ASCII) whose vertices start with x, y, z; standard library
only.
"""
import math
import re
import statistics
import struct
import sys

TYPES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
         "float": "f", "double": "d", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
         "int32": "i", "uint32": "I", "float32": "f", "float64": "d"}


def vertices(path):
    """The (x, y, z) of every vertex of the PLY at `path`."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"{path}: no end_header: not a PLY file")
            header.append(line.decode("ascii", "replace").strip())
            if header[-1] == "end_header":
                break
        fmt = next((h.split()[1] for h in header if h.startswith("format")), None)
        count, props, in_vertex = 0, [], False
        for h in header:
            words = h.split()
            if words[:1] == ["element"]:
                in_vertex = words[1] == "vertex"
                if in_vertex:
                    count = int(words[2])
            elif words[:1] == ["property"] and in_vertex:
                if words[1] == "list":
                    sys.exit(f"{path}: a list property among the vertices' is not supported")
                props.append(TYPES[words[1]])
        if len(props) < 3:
            sys.exit(f"{path}: the vertices have fewer than three properties")
        if fmt == "ascii":
            return [tuple(map(float, f.readline().split()[:3])) for _ in range(count)]
        if fmt != "binary_little_endian":
            sys.exit(f"{path}: format {fmt} is not supported (binary_little_endian or ascii)")
        record = "<" + "".join(props)
        size = struct.calcsize(record)
        data = f.read(size * count)
        if len(data) < size * count:
            sys.exit(f"{path}: the file ends inside its vertices")
        return [struct.unpack_from(record, data, i * size)[:3] for i in range(count)]


def main(argv):
    if len(argv) < 2 or argv[1] not in ("radius", "height"):
        sys.exit(__doc__)
    mode, path, *bounds = argv[1:]
    try:
        bounds = [float(b) for b in bounds]
    except ValueError:
        sys.exit(__doc__)
    if (mode == "radius" and len(bounds) != 4) or (mode == "height" and len(bounds) != 3):
        sys.exit(__doc__)
    vs = vertices(path)
    if mode == "radius":
        z0, z1, r0, r1 = bounds
        picked = [math.hypot(x, y) for x, y, z in vs if z0 < z < z1 and r0 < math.hypot(x, y) < r1]
        what = "median distance from the z axis"
    else:
        z0, z1, r1 = bounds
        picked = [z for x, y, z in vs if z0 < z < z1 and math.hypot(x, y) < r1]
        what = "median z"
    if not picked:
        sys.exit(f"{path}: no vertex in the region")
    print(f"{path}: {len(picked)} vertices, {what} {statistics.median(picked):.4f} mm")


if __name__ == "__main__":
    main(sys.argv)
