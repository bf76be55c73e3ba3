#!/usr/bin/env python3
"""Accuracy and speed of bdmorph's heat-method geodesics against the peers, on every shared
3D mesh, measured in one run against exact polyhedral distances. Run outside the test suite:

    python3 -m venv peers && peers/bin/pip install libigl==2.6.3 potpourri3d==1.4.0 \
        pygeodesic==0.1.11 numpy scipy
    cargo build --release --example geodesic_fields
    peers/bin/python tools/geodesic_compare.py --variant "neumann=--boundary neumann" \
        --variant "average=--boundary average" --variant "plain=--no-intrinsic-delaunay"
                                                                # the tables in BENCHMARKS.md
    peers/bin/python tools/geodesic_compare.py --variant "m0.5=--time-factor 0.5" \
        --meshes bunny --per-source                             # a variant, one mesh, detail

Meshes: every OBJ and OFF file under `closed3d/` and `disk3d/` of the shared data folder
(`--data`, default `../shared/data`). Sources: 10 per mesh (`--sources`), chosen by
farthest-point sampling in 3D (Euclidean) starting from vertex 0, so they are spread over the
mesh (on meshes with a boundary some end up on it; the table counts them);
`--skip-sources 10` takes the next 10 of the same sequence, an independent set.

Methods, each with its defaults (the peers: `t = h^2`, `h` the mean edge length):
  exact       bdmorph's exact solver (`bdmorph geodesic --exact`, window propagation; it
              agrees with pygeodesic's and libigl's MMP to about 1e-15 of the size,
              BENCHMARKS.md), or pygeodesic 0.1.11 with `--exact-from pygeodesic`; cached
              as .npy files in `--cache` (default `target/geodesic_compare/`)
  pp3d-robust potpourri3d 1.4.0 `MeshHeatMethodDistanceSolver(V, F, use_robust=True)`
              (geometry-central: mollified intrinsic Delaunay on the tufted cover)
  pp3d-plain  the same with `use_robust=False` (the mesh's own cotan Laplacian)
  libigl      libigl 2.6.3 `heat_geodesics_precompute` / `heat_geodesics_solve` (average of
              Neumann and Dirichlet heat on meshes with a boundary)
  bdmorph     `examples/geodesic_fields.rs` with default options; `--variant NAME=ARGS` adds
              runs with other options (ARGS as that example takes them)

Error of one field: the mean over all vertices but the source of |d - exact| / exact (the
relative error, as in the issue and `tests/geodesic.rs`). A table cell is the mean of that
over the mesh's sources. Times in the same run, in milliseconds: set-up, the median of 3;
query (one source, distance to every vertex), the median of all timed queries (`--repeats`
per source, after one untimed query each). The peers' queries include the Python call, a
few microseconds.
"""
import argparse
import glob
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from exact_geodesics import read_obj, read_off  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read_mesh(path):
    return read_off(path) if path.lower().endswith(".off") else read_obj(path)


def boundary_vertices(faces):
    """Vertices on an edge used by one face only."""
    edges = {}
    for f in faces:
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            key = (min(a, b), max(a, b))
            edges[key] = edges.get(key, 0) + 1
    on = set()
    for (a, b), count in edges.items():
        if count == 1:
            on.update((a, b))
    return on


def pick_sources(points, count, skip=0):
    """Farthest-point sampling (Euclidean) from vertex 0: deterministic and spread out. With
    `skip`, the `count` sources that follow the first `skip` of the same sequence."""
    chosen = [0]
    nearest = np.linalg.norm(points - points[0], axis=1)
    while len(chosen) < min(skip + count, len(points)):
        v = int(np.argmax(nearest))
        chosen.append(v)
        nearest = np.minimum(nearest, np.linalg.norm(points - points[v], axis=1))
    return chosen[skip:]


def exact_distances(path, points, faces, source, cache, solver="bdmorph"):
    name = os.path.relpath(path, start=os.path.dirname(os.path.dirname(os.path.dirname(path))))
    file = os.path.join(cache, name.replace(os.sep, "_") + f"_{source}.npy")
    if os.path.exists(file):
        return np.load(file)
    if solver == "pygeodesic":
        import pygeodesic.geodesic as geodesic

        algorithm = geodesic.PyGeodesicAlgorithmExact(points, faces)
        distances, _ = algorithm.geodesicDistances(np.array([source]), None)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "exact.txt")
            subprocess.run([os.path.join(REPO, "target", "release", "bdmorph"), "geodesic", path,
                            "--exact", "--source", str(source), "-o", out, "--quiet"],
                           check=True)
            distances = np.loadtxt(out)
    distances = np.asarray(distances, dtype=np.float64)
    os.makedirs(cache, exist_ok=True)
    np.save(file, distances)
    return distances


def relative_error(got, exact, source):
    mask = np.ones(len(exact), dtype=bool)
    mask[source] = False
    mask &= exact > 0
    return float(np.mean(np.abs(got[mask] - exact[mask]) / exact[mask]))


def time_peer(build, query, sources, repeats):
    """Set-up (median of 3) and one field per source, with the median query time."""
    setups = []
    for _ in range(3):
        started = time.perf_counter()
        solver = build()
        setups.append(time.perf_counter() - started)
    fields, queries = [], []
    for s in sources:
        fields.append(np.asarray(query(solver, s), dtype=np.float64))
        for _ in range(repeats):
            started = time.perf_counter()
            query(solver, s)
            queries.append(time.perf_counter() - started)
    return fields, statistics.median(setups), statistics.median(queries)


def peers(points, faces, sources, repeats):
    import igl
    import potpourri3d as pp3d

    faces64 = faces.astype(np.int64)

    def igl_build():
        data = igl.HeatGeodesicsData()
        igl.heat_geodesics_precompute(points, faces64, data)
        return data

    return {
        "pp3d-robust": time_peer(
            lambda: pp3d.MeshHeatMethodDistanceSolver(points, faces, use_robust=True),
            lambda s, v: s.compute_distance(v), sources, repeats),
        "pp3d-plain": time_peer(
            lambda: pp3d.MeshHeatMethodDistanceSolver(points, faces, use_robust=False),
            lambda s, v: s.compute_distance(v), sources, repeats),
        "libigl": time_peer(
            igl_build,
            lambda d, v: igl.heat_geodesics_solve(d, np.array([v], dtype=np.int64)),
            sources, repeats),
    }


def bdmorph(binary, path, points, sources, extra, repeats):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "fields.f64")
        command = [binary, path, "--sources", ",".join(map(str, sources)), "--out", out,
                   "--repeats", str(repeats)] + extra
        result = subprocess.run(command, capture_output=True, text=True, check=False)
        if result.returncode != 0:
            sys.exit(f"{' '.join(command)} failed:\n{result.stderr}")
        report = json.loads(result.stdout.strip().splitlines()[-1])
        if report["vertices"] != len(points) or not np.isclose(
                report["coordinate_sum"], points.sum(), rtol=1e-9, atol=1e-9):
            sys.exit(f"{path}: bdmorph read other vertices than this script")
        flat = np.fromfile(out, dtype="<f8")
    fields = list(flat.reshape(len(sources), len(points)))
    return fields, report["setup_seconds"], report["query_seconds"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=os.path.join(REPO, "..", "shared", "data"))
    parser.add_argument("--cache", default=os.path.join(REPO, "target", "geodesic_compare"))
    parser.add_argument("--bin", default=os.path.join(REPO, "target", "release", "examples",
                                                      "geodesic_fields"))
    parser.add_argument("--sources", type=int, default=10, help="sources per mesh")
    parser.add_argument("--skip-sources", type=int, default=0,
                        help="take the sources after this many of the sampling sequence "
                             "(a second, independent set of sources)")
    parser.add_argument("--repeats", type=int, default=20, help="timed queries per source")
    parser.add_argument("--meshes", default="", help="only meshes whose path contains this")
    parser.add_argument("--variant", action="append", default=[],
                        help="NAME=ARGS: also run bdmorph with these example arguments")
    parser.add_argument("--no-peers", action="store_true", help="bdmorph and exact only")
    parser.add_argument("--per-source", action="store_true", help="print every field's error")
    parser.add_argument("--exact-from", choices=["bdmorph", "pygeodesic"], default="bdmorph",
                        help="the exact reference (cached per solver-independent file name)")
    parser.add_argument("--extra", action="append", default=[],
                        help="another mesh file to include (e.g. target/exact_meshes/*.off)")
    args = parser.parse_args()
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: cargo build --release --example geodesic_fields")
    paths = sorted(p for sub in ("closed3d", "disk3d")
                   for p in glob.glob(os.path.join(args.data, sub, "**", "*"), recursive=True)
                   if p.lower().endswith((".obj", ".off")) and args.meshes in p)
    paths += args.extra
    if not paths:
        sys.exit(f"no meshes under {args.data}")
    variants = [("bdmorph", [])]
    for v in args.variant:
        name, _, rest = v.partition("=")
        variants.append((name, rest.split()))
    rows = []
    for path in paths:
        points, faces = read_mesh(path)
        sources = pick_sources(points, args.sources, args.skip_sources)
        on_boundary = boundary_vertices(faces)
        exact = [exact_distances(path, points, faces, s, args.cache, args.exact_from)
                 for s in sources]
        results = {} if args.no_peers else peers(points, faces, sources, args.repeats)
        for name, extra in variants:
            results[name] = bdmorph(args.bin, path, points, sources, extra, args.repeats)
        label = os.path.relpath(path, args.data)
        errors = {}
        per_source = {}
        for method, (fields, _, _) in results.items():
            per = [relative_error(f, e, s) for f, e, s in zip(fields, exact, sources)]
            per_source[method] = per
            errors[method] = float(np.mean(per))
            if args.per_source:
                print(f"{label} {method}: " + " ".join(
                    f"{s}{'b' if s in on_boundary else ''}:{x:.5f}" for s, x in zip(sources, per)))
        rows.append((label, len(points), sources, sum(s in on_boundary for s in sources),
                     errors, {m: (r[1], r[2]) for m, r in results.items()}, per_source))
        print(f"done {label}", file=sys.stderr, flush=True)
    methods = list(rows[0][4])
    peer_names = [m for m in methods if m in ("pp3d-robust", "pp3d-plain", "libigl")]
    print("\nMean relative error (mean over the sources of the mean over vertices of "
          "|d - exact| / exact)\n")
    head = "| mesh | V | sources (on boundary) | " + " | ".join(methods)
    if peer_names:
        head += " | bdmorph / best peer"
    print(head + " |")
    print("|---|---:|---|" + "---:|" * (len(methods) + bool(peer_names)))
    for label, n, sources, nb, errors, _, _ in rows:
        best = min(errors[m] for m in peer_names) if peer_names else None
        cells = []
        for m in methods:
            text = f"{errors[m]:.5f}"
            if best is not None and m in peer_names and errors[m] == best:
                text = f"*{text}*"
            cells.append(text)
        line = f"| {label} | {n} | {','.join(map(str, sources))} ({nb}) | " + " | ".join(cells)
        if best is not None:
            line += f" | {errors['bdmorph'] / best:.3f}"
        print(line + " |")
    print("\nSet-up / query, milliseconds (set-up: median of 3; query: median of "
          f"{args.repeats} per source)\n")
    head = "| mesh | " + " | ".join(methods)
    if peer_names:
        head += " | fastest peer query / bdmorph query"
    print(head + " |")
    print("|---|" + "---:|" * (len(methods) + bool(peer_names)))
    for label, _, _, _, _, times, _ in rows:
        cells = [f"{times[m][0] * 1e3:.1f} / {times[m][1] * 1e3:.3f}" for m in methods]
        line = f"| {label} | " + " | ".join(cells)
        if peer_names:
            fastest = min(times[m][1] for m in peer_names)
            line += f" | {fastest / times['bdmorph'][1]:.2f}"
        print(line + " |")

    if peer_names:
        # The figure that counts: per (mesh, source), bdmorph's error over the best peer's.
        print("\nPer source: bdmorph's error over the best peer's (worst source of each mesh)\n")
        print("| mesh | worst source | ratio | sources worse than the best peer |")
        print("|---|---:|---:|---:|")
        overall = []
        for label, _, sources, _, _, _, per in rows:
            ratios = [per["bdmorph"][i] / min(per[m][i] for m in peer_names)
                      for i in range(len(sources))]
            worst = int(np.argmax(ratios))
            overall += ratios
            print(f"| {label} | {sources[worst]} | {ratios[worst]:.3f} | "
                  f"{sum(r > 1 for r in ratios)} of {len(ratios)} |")
        print(f"\nWorst ratio over all {len(overall)} fields: {max(overall):.3f}; "
              f"worse than the best peer: {sum(r > 1 for r in overall)}; geometric mean "
              f"{float(np.exp(np.mean(np.log(overall)))):.3f}")


if __name__ == "__main__":
    main()
