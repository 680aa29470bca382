#!/usr/bin/python3
"""Open3D peer of `scan2cad reconstruct` (issue 3 benchmark): same stream in, mesh (mm) out.

    /usr/bin/python3 bench/peers/open3d_reconstruct.py STREAM_DIR OUT_MESH.ply \
        [--depth 9] [--trim-quantile 0.05] [--voxel MM]

Reads a scan2cad stream directory (docs/formats.md; depth sensor only), back-projects every
frame with Open3D (PinholeCameraIntrinsic, depth in mm, extrinsic = inverse camera-to-world
pose), merges the frames, voxel-downsamples (default voxel: the median nearest-neighbour
spacing of the first frame, as scan2cad does), estimates normals (KNN 24) oriented towards the
camera that saw each point, runs screened Poisson (depth 9) and removes the vertices whose
density is below the 5 % quantile. Prints one JSON line on stdout (points, timings in seconds).

Orientation: each point enters with the unit vector towards its frame's camera centre in its
normal; voxel_down_sample averages those; estimate_normals then flips every estimated normal to
agree with the normal already present (Open3D's documented behaviour), i.e. towards the sensor.

Use Debian's /usr/bin/python3 (python3-open3d, python3-opencv).
"""
import argparse
import json
import os
import sys
import tempfile
import time

import cv2
import numpy as np
import open3d as o3d


def fail(msg, code=2):
    print(f"open3d_reconstruct: error: {msg}", file=sys.stderr)
    sys.exit(code)


def read_stream(d):
    yaml = os.path.join(d, "stream.yaml")
    if not os.path.isfile(yaml):
        fail(f"{yaml}: no such file")
    fs = cv2.FileStorage(yaml, cv2.FILE_STORAGE_READ)
    if not fs.isOpened():
        fail(f"{yaml}: cannot be read as OpenCV FileStorage YAML")
    s = {
        "sensor": fs.getNode("sensor").string(),
        "width": int(fs.getNode("width").real()),
        "height": int(fs.getNode("height").real()),
        "depth_unit_mm": fs.getNode("depth_unit_mm").real(),
        "K": fs.getNode("camera_matrix").mat(),
        "dist": fs.getNode("dist_coeffs").mat(),
    }
    pu = fs.getNode("pose_unit_mm")
    s["pose_unit_mm"] = pu.real() if not pu.empty() else 1.0
    fs.release()
    if s["sensor"] != "depth":
        fail(f"{yaml}: sensor '{s['sensor']}' — this peer reads depth streams only")
    if s["K"] is None or s["K"].shape != (3, 3) or not s["depth_unit_mm"] > 0:
        fail(f"{yaml}: camera_matrix must be 3x3 and depth_unit_mm positive")

    def rows(path):
        if not os.path.isfile(path):
            fail(f"{path}: no such file")
        with open(path) as f:
            for ln in f:
                ln = ln.strip()
                if ln and not ln.startswith("#"):
                    yield ln.split()

    frames = [(float(r[0]), r[1]) for r in rows(os.path.join(d, "depth.txt"))]
    poses = [(float(r[0]), [float(x) for x in r[1:8]]) for r in rows(os.path.join(d, "poses.txt"))]
    if not poses:
        fail(f"{d}: poses.txt is empty; this peer needs poses")
    s["frames"] = []
    pts = np.array([p[0] for p in poses])
    for ts, fname in frames:
        k = int(np.argmin(np.abs(pts - ts)))
        if abs(pts[k] - ts) > 0.02:
            fail(f"{d}: frame {fname} has no pose within 20 ms")
        tx, ty, tz, qx, qy, qz, qw = poses[k][1]
        T = np.eye(4)
        T[:3, :3] = quat_to_matrix(qx, qy, qz, qw)
        T[:3, 3] = np.array([tx, ty, tz]) * s["pose_unit_mm"]
        s["frames"].append((os.path.join(d, fname), T))
    return s


def quat_to_matrix(x, y, z, w):
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def frame_cloud(s, path, T):
    depth = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if depth is None or depth.dtype != np.uint16 or depth.ndim != 2:
        fail(f"{path}: not a 16-bit single-channel PNG")
    h, w = depth.shape
    K = s["K"]
    dist = s["dist"]
    if dist is not None and np.any(np.abs(dist) > 0):
        # Open3D's pinhole model has no distortion: undistort the rays with OpenCV instead.
        v, u = np.nonzero(depth)
        z = depth[v, u].astype(np.float64) * s["depth_unit_mm"]
        uv = np.stack([u, v], axis=1).astype(np.float64).reshape(-1, 1, 2)
        xy = cv2.undistortPoints(uv, K, dist).reshape(-1, 2)
        cam = np.stack([xy[:, 0] * z, xy[:, 1] * z, z], axis=1)
        world = cam @ T[:3, :3].T + T[:3, 3]
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(world))
    else:
        intr = o3d.camera.PinholeCameraIntrinsic(w, h, K[0, 0], K[1, 1], K[0, 2], K[1, 2])
        pcd = o3d.geometry.PointCloud.create_from_depth_image(
            o3d.geometry.Image(np.ascontiguousarray(depth)), intr, extrinsic=np.linalg.inv(T),
            depth_scale=1.0 / s["depth_unit_mm"], depth_trunc=1e12, stride=1)
    # Unit vectors towards the camera centre ride in the normals until normals are estimated.
    p = np.asarray(pcd.points)
    view = T[:3, 3][None, :] - p
    view /= np.maximum(np.linalg.norm(view, axis=1, keepdims=True), 1e-12)
    pcd.normals = o3d.utility.Vector3dVector(view)
    return pcd


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("stream")
    ap.add_argument("out")
    ap.add_argument("--depth", type=int, default=9, help="Poisson octree depth (default 9)")
    ap.add_argument("--trim-quantile", type=float, default=0.05,
                    help="drop vertices whose Poisson density is below this quantile (default 0.05)")
    ap.add_argument("--voxel", type=float, default=0.0,
                    help="voxel size, mm (default: median NN spacing of the first frame)")
    ap.add_argument("--knn", type=int, default=24, help="neighbours for normal estimation (default 24)")
    a = ap.parse_args()
    if not a.out.lower().endswith((".ply", ".stl", ".obj", ".off")):
        fail(f"{a.out}: the mesh must be .ply .stl .obj or .off")
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    t = {}
    t0 = time.perf_counter()
    s = read_stream(a.stream)
    merged = o3d.geometry.PointCloud()
    spacing = 0.0
    for i, (path, T) in enumerate(s["frames"]):
        pcd = frame_cloud(s, path, T)
        if i == 0 and len(pcd.points) > 1:
            spacing = float(np.median(np.asarray(pcd.compute_nearest_neighbor_distance())))
        merged += pcd
    points_in = len(merged.points)
    if points_in < 10:
        fail(f"{a.stream}: only {points_in} valid points")
    t1 = time.perf_counter()
    t["read_backproject"] = t1 - t0

    voxel = a.voxel if a.voxel > 0 else spacing
    fused = merged.voxel_down_sample(voxel)
    del merged
    t2 = time.perf_counter()
    t["voxel"] = t2 - t1

    fused.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=a.knn))
    fused.normalize_normals()
    t3 = time.perf_counter()
    t["normals"] = t3 - t2

    mesh, dens = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(fused, depth=a.depth)
    t4 = time.perf_counter()
    t["poisson"] = t4 - t3
    faces_before = len(mesh.triangles)

    dens = np.asarray(dens)
    if a.trim_quantile > 0:
        mesh.remove_vertices_by_mask(dens < np.quantile(dens, a.trim_quantile))
    mesh.remove_unreferenced_vertices()
    t5 = time.perf_counter()
    t["trim"] = t5 - t4

    out_dir = os.path.dirname(os.path.abspath(a.out))
    fd, tmp = tempfile.mkstemp(prefix=".o3d_", suffix=os.path.splitext(a.out)[1], dir=out_dir)
    os.close(fd)
    try:
        mesh.compute_vertex_normals()
        if not o3d.io.write_triangle_mesh(tmp, mesh, write_ascii=False):
            fail(f"{a.out}: write failed", 4)
        os.replace(tmp, a.out)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    t6 = time.perf_counter()
    t["write"] = t6 - t5

    print(json.dumps({
        "method": "open3d", "open3d_version": o3d.__version__, "stream": a.stream, "output": a.out,
        "frames": len(s["frames"]), "points_in": points_in, "points_fused": len(fused.points),
        "spacing_mm": round(spacing, 6), "voxel_mm": round(voxel, 6), "poisson_depth": a.depth,
        "trim_quantile": a.trim_quantile, "faces_before_trim": faces_before,
        "faces": len(mesh.triangles), "vertices": len(mesh.vertices),
        "seconds": {k: round(v, 4) for k, v in t.items()}, "total_seconds": round(t6 - t0, 4)}))


if __name__ == "__main__":
    main()
