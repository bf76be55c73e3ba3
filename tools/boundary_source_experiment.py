#!/usr/bin/env python3
"""What could `--boundary dirichlet|average` mean for a source on the boundary? Zero heat on
the boundary contradicts a source there, so the only candidate is zero heat on the rest of
the boundary. This measures it against zero flux (Neumann) on the shared disk meshes, with
the plain heat method (libigl's cotan Laplacian, barycentric masses, t = h^2, SciPy solves)
so that only the boundary conditions differ. Run outside the test suite:

    peers/bin/python tools/boundary_source_experiment.py     # venv as in geodesic_compare.py

Sources: the boundary vertices among the first 10 of geodesic_compare.py's farthest-point
sequence on each mesh of `disk3d/`. Error: as in geodesic_compare.py (mean relative error
against pygeodesic's exact distances, cached in the same folder). Prints one line per source:
Neumann, Dirichlet on the boundary but the source, and the mean of the two heats.
"""
import argparse
import glob
import os
import sys

import numpy as np
import scipy.sparse.linalg as sla

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geodesic_compare as g  # noqa: E402


def distance(points, faces, source, mode):
    import igl

    laplacian = -igl.cotmatrix(points, faces)
    mass = igl.massmatrix(points, faces, igl.MASSMATRIX_TYPE_BARYCENTRIC)
    h = igl.avg_edge_length(points, faces)
    heat_op = (mass + h * h * laplacian).tocsc()
    n = len(points)
    delta = np.zeros(n)
    delta[source] = 1.0
    neumann = sla.spsolve(heat_op, delta)
    if mode == "neumann":
        u = neumann
    else:
        fixed = sorted(g.boundary_vertices(faces) - {source})
        free = np.setdiff1d(np.arange(n), fixed)
        dirichlet = np.zeros(n)
        dirichlet[free] = sla.spsolve(heat_op[free][:, free].tocsc(), delta[free])
        u = dirichlet if mode == "dirichlet" else 0.5 * (neumann + dirichlet)
    grad = igl.grad(points, faces)
    gu = (grad @ u).reshape(3, -1).T
    norm = np.linalg.norm(gu, axis=1)[:, None]
    x = -gu / np.where(norm > 0, norm, 1.0)  # zero where u is flat, as bdmorph does
    area = igl.doublearea(points, faces) / 2
    div = -grad.T @ (np.tile(area, 3) * x.T.reshape(-1))
    keep = np.arange(1, n)
    phi = np.zeros(n)
    phi[keep] = sla.spsolve(laplacian[keep][:, keep].tocsc(), -div[keep])
    return phi - phi[source]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", default=os.path.join(g.REPO, "..", "shared", "data"))
    parser.add_argument("--cache", default=os.path.join(g.REPO, "target", "geodesic_compare"))
    args = parser.parse_args()
    ratios = {"dirichlet": [], "average": []}
    print("| mesh | source | neumann | dirichlet but the source | average |")
    print("|---|---:|---:|---:|---:|")
    for path in sorted(glob.glob(os.path.join(args.data, "disk3d", "**", "*"), recursive=True)):
        if not path.lower().endswith((".obj", ".off")):
            continue
        points, faces = g.read_mesh(path)
        on_boundary = g.boundary_vertices(faces)
        for s in g.pick_sources(points, 10):
            if s not in on_boundary:
                continue
            exact = g.exact_distances(path, points, faces, s, args.cache)
            err = {m: g.relative_error(distance(points, faces, s, m), exact, s)
                   for m in ("neumann", "dirichlet", "average")}
            for m in ratios:
                ratios[m].append(err[m] / err["neumann"])
            print(f"| {os.path.relpath(path, args.data)} | {s} | {err['neumann']:.4f} | "
                  f"{err['dirichlet']:.4f} | {err['average']:.4f} |")
    for m, r in ratios.items():
        r = np.array(r)
        print(f"\n{m} / neumann over {len(r)} boundary sources: geometric mean "
              f"{np.exp(np.mean(np.log(r))):.2f}, range {r.min():.2f}-{r.max():.2f}, "
              f"better on {int((r < 1).sum())}")


if __name__ == "__main__":
    main()
