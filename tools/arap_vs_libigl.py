#!/usr/bin/env python3
"""Local/global ARAP parameterisation side by side: `bdmorph param --method arap` (the whole
command: reading the mesh, set-up, 100 iterations, no output file) against libigl's whole run
as in its tutorial 503 (harmonic start with the boundary on a circle by arc length, then
`arap_precomputation` and `arap_solve` with 100 iterations), in one run of this script, so
that the machine's load is the same for both. Not run by the tests.

    /path/to/venv/bin/python tools/arap_vs_libigl.py [--repeat 5] [--bin target/release/bdmorph] \
        ../shared/data/disk3d/ustc-cg/Cow_dABF.obj ../shared/data/disk3d/libigl/camelhead.off

Needs libigl 2.6.3 (`pip install libigl==2.6.3 numpy scipy`). For each mesh it prints the
median wall-clock time over the repeats of: our command (and its own `setup_seconds` and
`seconds` from `--stats`), libigl's whole run split into reading, start (boundary loop,
circle, harmonic), `arap_precomputation` and `arap_solve`; and for both final maps,
measured here the same way: flipped triangles and the area-weighted mean ARAP energy
`(s1 - 1)^2 + (s2 - 1)^2` per triangle, scale included (as both solve it). Last, libigl
configured as we are (one boundary vertex pinned instead of the tutorial's `with_dynamics`
inertia term), which shows where a difference in flipped triangles comes from.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import igl
import numpy as np


def read_obj_uv(path):
    """Vertices, per-vertex texture coordinates and faces of `bdmorph param -o x.obj`."""
    v, t, f = [], [], []
    with open(path) as fh:
        for line in fh:
            s = line.split()
            if not s:
                continue
            if s[0] == "v":
                v.append([float(x) for x in s[1:4]])
            elif s[0] == "vt":
                t.append([float(x) for x in s[1:3]])
            elif s[0] == "f":
                f.append([int(x.split("/")[0]) - 1 for x in s[1:4]])
    return np.array(v), np.array(t), np.array(f)


def jacobians(v, f, uv):
    """Per triangle, the 2x2 Jacobian of the map from its isometric layout, and its area."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    xb = np.linalg.norm(e1, axis=1)
    xc = (e1 * e2).sum(1) / xb
    yc = np.sqrt(np.maximum((e2 * e2).sum(1) - xc**2, 0.0))
    ua, ub, uc = uv[f[:, 0]], uv[f[:, 1]], uv[f[:, 2]]
    d1, d2 = ub - ua, uc - ua
    j = np.zeros((len(f), 2, 2))
    j[:, :, 0] = d1 / xb[:, None]
    j[:, :, 1] = (d2 - d1 * (xc / xb)[:, None]) / yc[:, None]
    return j, 0.5 * xb * yc


def quality(v, f, uv):
    j, area = jacobians(v, f, uv)
    det = np.linalg.det(j)
    s = np.linalg.svd(j, compute_uv=False)
    # Signed singular values: the smaller takes the sign of det.
    s2 = np.where(det < 0, -s[:, 1], s[:, 1])
    e = (s[:, 0] - 1.0) ** 2 + (s2 - 1.0) ** 2
    return int((det <= 0).sum()), float((area * e).sum() / area.sum())


def libigl_run(path, iterations):
    times = {}
    t0 = time.perf_counter()
    v, f = igl.read_triangle_mesh(path)
    t1 = time.perf_counter()
    bnd = igl.boundary_loop(f)
    bnd_uv = igl.map_vertices_to_circle(v, bnd)
    uv0 = igl.harmonic(v, f, bnd, bnd_uv, 1)
    t2 = time.perf_counter()
    data = igl.ARAPData()
    data.with_dynamics = True
    data.max_iter = iterations
    b = np.zeros(0, dtype=np.int32)
    igl.arap_precomputation(v, f, 2, b, data)
    t3 = time.perf_counter()
    uv = igl.arap_solve(np.zeros((0, 2)), data, uv0)
    t4 = time.perf_counter()
    times.update(read=t1 - t0, start=t2 - t1, precomputation=t3 - t2, solve=t4 - t3, whole=t4 - t0)
    return v, f, uv0, uv, times


def libigl_pinned(v, f, uv0, iterations):
    """libigl's ARAP configured as ours: one boundary vertex pinned, no dynamics term."""
    bnd = igl.boundary_loop(f)
    data = igl.ARAPData()
    data.with_dynamics = False
    data.max_iter = iterations
    b = np.array([bnd[0]], dtype=np.int32)
    igl.arap_precomputation(v, f, 2, b, data)
    return igl.arap_solve(uv0[b], data, uv0)


def ours_run(binary, path, iterations, out):
    t0 = time.perf_counter()
    r = subprocess.run(
        [binary, "param", path, "--method", "arap", "--iterations", str(iterations), "--stats", "-q"],
        capture_output=True,
        text=True,
    )
    t1 = time.perf_counter()
    if r.returncode != 0:
        sys.exit(f"bdmorph failed: {r.stderr}")
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    # The map itself, for the side-by-side quality (not timed).
    subprocess.run(
        [binary, "param", path, "--method", "arap", "--iterations", str(iterations), "-q", "-o", out],
        check=True,
    )
    return summary, t1 - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--iterations", type=int, default=100)
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "bdmorph"))
    a = ap.parse_args()
    print(f"load average at start: {os.getloadavg()}")
    for path in a.meshes:
        mine, theirs = [], []
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "arap.obj")
            for _ in range(a.repeat):
                # Alternate, so that both see the same load.
                summary, wall = ours_run(a.bin, path, a.iterations, out)
                mine.append((wall, summary["setup_seconds"], summary["seconds"]))
                v, f, uv0, uv, times = libigl_run(path, a.iterations)
                theirs.append(times)
            vo, to, fo = read_obj_uv(out)
            our_flips, our_e = quality(vo, fo, to)
        their_flips, their_e = quality(v, f, uv)
        start_flips, _ = quality(v, f, uv0)
        med = lambda xs: statistics.median(xs)
        print(f"{os.path.basename(path)}: {len(v)} vertices, {len(f)} faces, {a.iterations} iterations, median of {a.repeat}")
        print(
            f"  bdmorph param --method arap: whole command {med([m[0] for m in mine]):.4f} s "
            f"(set-up {med([m[1] for m in mine]):.4f} s, iterations {med([m[2] for m in mine]):.4f} s); "
            f"E_ARAP {our_e:.5f}, {our_flips} flipped"
        )
        print(
            f"  libigl: whole run {med([t['whole'] for t in theirs]):.4f} s (read {med([t['read'] for t in theirs]):.4f}, "
            f"harmonic start {med([t['start'] for t in theirs]):.4f}, arap_precomputation {med([t['precomputation'] for t in theirs]):.4f}, "
            f"arap_solve {med([t['solve'] for t in theirs]):.4f}); E_ARAP {their_e:.5f}, {their_flips} flipped "
            f"(harmonic start: {start_flips} flipped)"
        )
        print(f"  ratio (ours / libigl, whole): {med([m[0] for m in mine]) / med([t['whole'] for t in theirs]):.2f}")
        pinned_flips, pinned_e = quality(v, f, libigl_pinned(v, f, uv0, a.iterations))
        print(
            f"  libigl configured as ours (one vertex pinned, with_dynamics off; not timed): "
            f"E_ARAP {pinned_e:.5f}, {pinned_flips} flipped"
        )
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
