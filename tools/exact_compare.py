#!/usr/bin/env python3
"""Exact geodesic distances: bdmorph's window propagation against libigl's exact_geodesic and
pygeodesic (both Kirsanov's MMP), on the shared meshes: agreement (largest difference over
the mesh's bounding-box diagonal) and time per query (median of 3, one source).

    python3 -m venv peers && peers/bin/pip install libigl==2.6.3 pygeodesic==0.1.11 numpy
    cargo build --release
    peers/bin/python tools/exact_compare.py [MESH ...]
"""
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import igl
import numpy as np
import pygeodesic.geodesic as pyg

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT.parent / "shared" / "data"
BIN = ROOT / "target" / "release" / "bdmorph"
DEFAULT = [
    "closed3d/odedstein/sphere.obj",
    "disk3d/ustc-cg/Nefertiti_face.obj",
    "closed3d/libigl/bunny.off",
    "closed3d/libigl/fandisk.off",
    "disk3d/libigl/camelhead.off",
]


def median_time(fn, runs=3):
    times, out = [], None
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return sorted(times)[len(times) // 2], out


def main():
    meshes = sys.argv[1:] or DEFAULT
    print("| mesh | V | libigl | pygeodesic | bdmorph | fastest peer / bdmorph | max diff / size (libigl, pygeodesic) |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for rel in meshes:
        path = Path(rel) if Path(rel).is_file() else DATA / rel
        v, f = igl.read_triangle_mesh(str(path))
        size = np.linalg.norm(v.max(0) - v.min(0))
        src = 0
        # libigl takes minutes above 50K vertices: one run there.
        t_igl, d_igl = median_time(lambda: igl.exact_geodesic(v, f, VS=np.array([src]), VT=np.arange(len(v))),
                                   runs=1 if len(v) > 50_000 else 3)
        t_pyg, d_pyg = median_time(lambda: pyg.PyGeodesicAlgorithmExact(v, f).geodesicDistances(np.array([src]), None)[0])
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "d.txt"
            runs = []
            for _ in range(3):
                res = subprocess.run([str(BIN), "geodesic", str(path), "--exact", "--source", str(src),
                                      "-o", str(out), "--stats", "--quiet"], check=True,
                                     capture_output=True, text=True)
                runs.append(json.loads(res.stdout))
            ours = np.loadtxt(out)
        t_ours = sorted(r["setup_seconds"] + r["query_seconds"] for r in runs)[1]
        e_igl = np.max(np.abs(ours - d_igl)) / size
        e_pyg = np.max(np.abs(ours - d_pyg)) / size
        print(f"| {rel} | {len(v)} | {t_igl*1e3:.1f} ms | {t_pyg*1e3:.1f} ms | {t_ours*1e3:.1f} ms | "
              f"{min(t_igl, t_pyg)/t_ours:.2f} | {e_igl:.1e}, {e_pyg:.1e} |", flush=True)


if __name__ == "__main__":
    main()
