"""Benchmarks of the Python package, each against a baseline in the same run:

1. Per-frame cost from Python (``Morph.frame`` in a loop) against the same frames computed
   by the Rust program (``bdmorph morph --frames N --stats``: each frame's own time), on a
   generated strip of about 10K vertices (goal: Python within 5% of Rust).
2. Heat-method geodesics against potpourri3d and libigl (set-up, one query), on shared meshes.
3. Parameterisation (LSCM; ARAP, 100 iterations) against libigl, on shared meshes.

Peers are optional (skipped with a note when not installed). Medians of repeated runs.

    python3 -m venv peers && peers/bin/pip install ./python libigl==2.6.3 potpourri3d==1.4.0
    cargo build --release
    peers/bin/python python/benchmarks/bench.py [--repeat 5] [--bin target/release/bdmorph]
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import bdmorph

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared" / "data"
sys.path.insert(0, str(REPO / "python" / "tests"))
from conftest import bend, grid  # noqa: E402  (the tests' mesh makers)


def median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        fn()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def frames(binary, repeat):
    V0, F = grid(200, 50, (8.0, 2.0))
    V1 = bend(V0, 2.0)
    n_frames = 41
    ts = np.linspace(0, 1, n_frames)
    with tempfile.TemporaryDirectory() as tmp:
        a, b = pathlib.Path(tmp, "a.obj"), pathlib.Path(tmp, "b.obj")
        bdmorph.write_obj(a, V0, F)
        bdmorph.write_obj(b, V1, F)
        rust_runs, python_runs = [], []
        for _ in range(repeat):
            out = subprocess.run([str(binary), "morph", str(a), str(b), "--frames", str(n_frames),
                                  "--stats"], capture_output=True, text=True, check=True).stdout
            per = [json.loads(line)["seconds"] for line in out.splitlines() if line.startswith("{")]
            rust_runs.append(statistics.median(per[1:]))
            m = bdmorph.Morph(V0, V1, F)
            per = []
            for t in ts:
                started = time.perf_counter()
                m.frame(t)
                per.append(time.perf_counter() - started)
            python_runs.append(statistics.median(per[1:]))
    rust, python = statistics.median(rust_runs), statistics.median(python_runs)
    print(f"frames: {len(V0)} vertices, {n_frames} frames, median per frame over {repeat} runs: "
          f"Rust {rust * 1e3:.3f} ms, Python {python * 1e3:.3f} ms, Python / Rust {python / rust:.3f}")
    return {"vertices": len(V0), "rust_ms": rust * 1e3, "python_ms": python * 1e3,
            "ratio": python / rust}


def geodesics(repeat):
    try:
        import igl
        import potpourri3d as pp3d
    except ImportError:
        print("geodesics: potpourri3d/libigl not installed; skipped")
        return None
    rows = []
    for rel in ["closed3d/libigl/bunny.off", "disk3d/libigl/camelhead.off"]:
        path = SHARED / rel
        if not path.is_file():
            print(f"geodesics: {path} missing (the shared data folder); skipped")
            continue
        V, F = bdmorph.read_mesh(path)
        F32 = F.astype(np.int32)
        ours = {"setup": median_time(lambda: bdmorph.HeatGeodesics(V, F), repeat)}
        g = bdmorph.HeatGeodesics(V, F)
        ours["query"] = median_time(lambda: g.distance([0]), repeat)
        pp = {"setup": median_time(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F32), repeat)}
        solver = pp3d.MeshHeatMethodDistanceSolver(V, F32)
        pp["query"] = median_time(lambda: solver.compute_distance(0), repeat)

        def igl_setup():
            data = igl.HeatGeodesicsData()
            igl.heat_geodesics_precompute(V, F, data)
            return data

        ig = {"setup": median_time(igl_setup, repeat)}
        data = igl_setup()
        ig["query"] = median_time(lambda: igl.heat_geodesics_solve(data, np.array([0])), repeat)
        row = {"mesh": rel, "vertices": len(V), "bdmorph": ours, "potpourri3d": pp, "libigl": ig}
        rows.append(row)
        print(f"geodesics {rel} ({len(V)} vertices): set-up / query ms: "
              + ", ".join(f"{k} {v['setup'] * 1e3:.1f} / {v['query'] * 1e3:.2f}"
                          for k, v in [("bdmorph", ours), ("potpourri3d", pp), ("libigl", ig)]))
    return rows


def parameterisations(repeat):
    try:
        import igl
    except ImportError:
        print("parameterisation: libigl not installed; skipped")
        return None
    rows = []
    for rel in ["disk3d/libigl/camelhead.off", "disk3d/ustc-cg/Cow_dABF.obj"]:
        path = SHARED / rel
        if not path.is_file():
            print(f"parameterisation: {path} missing (the shared data folder); skipped")
            continue
        V, F = bdmorph.read_mesh(path)
        lscm_ours = median_time(lambda: bdmorph.parameterize(V, F, "lscm"), repeat)
        bnd = igl.boundary_loop(F)
        b = np.array([bnd[0], bnd[len(bnd) // 2]], dtype=np.int64)
        bc = np.array([[0.0, 0.0], [1.0, 0.0]])
        lscm_igl = median_time(lambda: igl.lscm(V, F, b, bc), repeat)

        def igl_arap():
            bnd_uv = igl.map_vertices_to_circle(V, bnd)
            uv0 = igl.harmonic(V, F, bnd, bnd_uv, 1)
            data = igl.ARAPData()
            data.with_dynamics = True
            data.max_iter = 100
            igl.arap_precomputation(V, F, 2, np.zeros(0, dtype=np.int64), data)
            return igl.arap_solve(np.zeros((0, 2)), data, uv0)

        arap_ours = median_time(lambda: bdmorph.parameterize(V, F, "arap", iterations=100), repeat)
        arap_igl = median_time(igl_arap, repeat)
        rows.append({"mesh": rel, "vertices": len(V), "lscm_ms": [lscm_ours * 1e3, lscm_igl * 1e3],
                     "arap100_ms": [arap_ours * 1e3, arap_igl * 1e3]})
        print(f"parameterisation {rel} ({len(V)} vertices), bdmorph / libigl ms: "
              f"LSCM {lscm_ours * 1e3:.1f} / {lscm_igl * 1e3:.1f}, "
              f"ARAP x100 {arap_ours * 1e3:.1f} / {arap_igl * 1e3:.1f}")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--bin", default=str(REPO / "target" / "release" / "bdmorph"))
    parser.add_argument("--json", help="also write the results here")
    args = parser.parse_args()
    results = {"frames": frames(args.bin, args.repeat), "geodesics": geodesics(args.repeat),
               "parameterisation": parameterisations(args.repeat)}
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
