"""ExactGeodesics and geodesic_distance(exact=True): the straight line on a flat mesh, paths as
long as the distances, and libigl's exact_geodesic (Kirsanov's MMP) on a sphere and on the
shared meshes, to 1e-9 of the mesh's size."""
import numpy as np
import pytest

import bdmorph
from conftest import shared


def grid(n=12, seed=3):
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.linspace(0, 2, n + 1), np.linspace(0, 1, n + 1))
    V = np.stack([xs.ravel(), ys.ravel()], axis=1)
    inner = (V[:, 0] > 0) & (V[:, 0] < 2) & (V[:, 1] > 0) & (V[:, 1] < 1)
    V[inner] += (rng.random((inner.sum(), 2)) - 0.5) * 0.3 / n
    F = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F)


def test_flat_distances_are_straight_lines_and_paths_are_as_long():
    V, F = grid()
    g = bdmorph.ExactGeodesics(V, F)
    for s in [0, 40, len(V) - 1]:
        d = g.distance([s])
        assert np.max(np.abs(d - np.linalg.norm(V - V[s], axis=1))) < 1e-12
    d = g.distance(5)
    far = int(np.argmax(d))
    p = g.path(5, far)
    assert p.shape[1] == 3 and np.allclose(p[0, :2], V[5]) and np.allclose(p[-1, :2], V[far])
    assert abs(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)) - d[far]) < 1e-9
    assert np.array_equal(bdmorph.geodesic_distance(V, F, [7], exact=True), g.distance([7]))
    assert g.distances_each([0, 7]).shape == (2, len(V))
    with pytest.raises(bdmorph.GeodesicError):
        g.path(0, len(V))
    with pytest.raises(bdmorph.GeodesicError):
        bdmorph.geodesic_distance(V, F, [0], exact=True, time_factor=1.0)


def sphere(subdivisions=3):
    t = (1 + 5 ** 0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(subdivisions):
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


def against_libigl(V, F, sources):
    igl = pytest.importorskip("igl")
    g = bdmorph.ExactGeodesics(V, F)
    size = np.linalg.norm(V.max(0) - V.min(0))
    for s in sources:
        want = igl.exact_geodesic(V, F.astype(np.int64), VS=np.array([s]), VT=np.arange(len(V)))
        worst = np.max(np.abs(g.distance([s]) - want)) / size
        assert worst < 1e-9, (s, worst)


def test_a_sphere_matches_libigl():
    V, F = sphere(3)
    against_libigl(V, F, [0, 100, 641])


def test_shared_meshes_match_libigl():
    for rel in ["disk3d/ustc-cg/Nefertiti_face.obj", "closed3d/libigl/bunny.off"]:
        V, F = bdmorph.read_mesh(shared(rel))
        against_libigl(np.asarray(V, float), np.asarray(F), [0, len(V) // 2])
