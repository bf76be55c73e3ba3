#!/usr/bin/env python3
"""Exact polyhedral geodesic distances (MMP algorithm, via pygeodesic from PyPI) from one
source vertex to every vertex of a triangle mesh, written one per line in vertex order.

These files are reference data for tests and benchmarks of the heat method; they are
generated here, outside the test run:

    pip install pygeodesic==0.1.11
    python3 tools/exact_geodesics.py ../shared/data/disk3d/libigl/camelhead.off 0 \
        tests/data/camelhead_exact_0.txt

Reads OBJ (`v`, `f` with any `a/b/c` form) and OFF. Distances are written with 9 significant
digits; the header lines start with '#'.
"""
import sys

import numpy as np
import pygeodesic.geodesic as geodesic


def read_off(path):
    words = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0]
            words.extend(line.split())
    assert words[0].upper() == "OFF", path
    nv, nf = int(words[1]), int(words[2])
    i = 4
    points = np.array([[float(w) for w in words[i + 3 * k: i + 3 * k + 3]] for k in range(nv)])
    i += 3 * nv
    faces = []
    for _ in range(nf):
        n = int(words[i])
        assert n == 3, "triangles only"
        faces.append([int(w) for w in words[i + 1: i + 4]])
        i += 1 + n
    return points, np.array(faces, dtype=np.int32)


def read_obj(path):
    points, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                points.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                assert len(idx) == 3, "triangles only"
                faces.append([i - 1 if i > 0 else len(points) + i for i in idx])
    return np.array(points), np.array(faces, dtype=np.int32)


def main():
    path, source, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    points, faces = read_off(path) if path.lower().endswith(".off") else read_obj(path)
    algorithm = geodesic.PyGeodesicAlgorithmExact(points, faces)
    distances, _ = algorithm.geodesicDistances(np.array([source]), None)
    with open(out, "w") as f:
        f.write(f"# exact polyhedral geodesic distances from vertex {source} of {path.split('/')[-1]}\n")
        f.write(f"# {len(points)} vertices, {len(faces)} faces; pygeodesic 0.1.11 (MMP); tools/exact_geodesics.py\n")
        for d in distances:
            f.write(f"{d:.9g}\n")


if __name__ == "__main__":
    main()
