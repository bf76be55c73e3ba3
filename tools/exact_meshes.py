#!/usr/bin/env python3
"""Meshes made in code for tools/exact_compare.py and tools/geodesic_compare.py (`--extra`),
written as OFF into target/exact_meshes/: a bumpy sphere of 10242 and 40962 vertices (an
icosphere pushed in and out by a sum of waves, so about half its vertices are saddles), a
bumpy torus of 102400 vertices, and two adversarial meshes with a boundary: a wavy strip of
slivers (cells 10 times longer than wide, rows sheared) and a saddle-shaped disk whose
density varies 30-fold from the centre to the rim."""
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "target" / "exact_meshes"


def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(level):
        cache, G = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = V[a] + V[b]
                V.append(m / np.linalg.norm(m))
                cache[key] = len(V) - 1
            return cache[key]

        for a, b, c in F:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            G += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        F = G
    return np.array(V), np.array(F)


def bumps(P):
    x, y, z = P[:, 0], P[:, 1], P[:, 2]
    return 1 + 0.08 * np.sin(5 * x + 1) * np.sin(4 * y) + 0.05 * np.cos(7 * z + 2 * x)


def torus(nu, nv):
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    r = 0.35 * (1 + 0.15 * np.sin(6 * u) * np.cos(5 * v))
    P = np.stack([(1 + r * np.cos(v)) * np.cos(u), (1 + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1)
    idx = lambda i, j: (i % nu) * nv + (j % nv)
    F = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            F += [[a, b, c], [a, c, d]]
    return P.reshape(-1, 3), np.array(F)


def sliver_strip(nx=100, ny=10):
    V = []
    for j in range(ny + 1):
        shift = 0.35 if j % 2 else 0.0
        for i in range(nx + 1):
            x = i + (shift if 0 < i < nx else 0.0)
            x = 10.0 * x / nx
            V.append([x, j / ny, 0.2 * np.sin(x)])
    idx = lambda i, j: j * (nx + 1) + i
    F = []
    for j in range(ny):
        for i in range(nx):
            F += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    return np.array(V), np.array(F)


def graded_disk(rings=30, around=64):
    V = [[0.0, 0.0]]
    for k in range(1, rings + 1):
        r = (k / rings) ** 2
        for i in range(around):
            a = 2 * np.pi * (i + 0.5 * (k % 2)) / around
            V.append([r * np.cos(a), r * np.sin(a)])
    V = np.array(V)
    F = [[0, 1 + i, 1 + (i + 1) % around] for i in range(around)]
    for k in range(rings - 1):
        a0, a1 = 1 + k * around, 1 + (k + 1) * around
        for i in range(around):
            j = (i + 1) % around
            if k % 2 == 0:
                F += [[a0 + i, a1 + i, a0 + j], [a0 + j, a1 + i, a1 + j]]
            else:
                F += [[a0 + i, a1 + i, a1 + j], [a0 + i, a1 + j, a0 + j]]
    z = 0.4 * (V[:, 0] ** 2 - V[:, 1] ** 2)
    return np.column_stack([V, z]), np.array(F)


def write_off(path, V, F):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(V)} {len(F)} 0\n")
        np.savetxt(f, V, fmt="%.17g")
        np.savetxt(f, np.hstack([np.full((len(F), 1), 3), F]), fmt="%d")


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    for level in (5, 6):
        V, F = icosphere(level)
        write_off(OUT / f"bumpy_sphere_{len(V)}.off", V * bumps(V)[:, None], F)
    V, F = torus(640, 160)
    write_off(OUT / f"bumpy_torus_{len(V)}.off", V, F)
    V, F = sliver_strip()
    write_off(OUT / f"sliver_strip_{len(V)}.off", V, F)
    V, F = graded_disk()
    write_off(OUT / f"graded_disk_{len(V)}.off", V, F)
    print("\n".join(str(p) for p in sorted(OUT.glob("*.off"))))


if __name__ == "__main__":
    main()
