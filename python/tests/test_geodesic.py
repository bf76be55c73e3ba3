"""HeatGeodesics against the command line's distance files (bit for bit: the same engine and
text that reads back exactly), its options, and its errors."""

import numpy as np
import pytest

import bdmorph
from conftest import bump, grid, read_numbers, shared


def fields(path):
    return np.array([[float(x) for x in line.split()] for line in open(path) if line.strip()])


def test_distances_equal_the_command_lines_on_shared_meshes(tmp_path, cli):
    for relative in ["closed3d/libigl/sphere.obj", "disk3d/libigl/camelhead.off"]:
        mesh = shared(relative)
        V, F = bdmorph.read_mesh(mesh)
        g = bdmorph.HeatGeodesics(V, F)
        cli("geodesic", mesh, "--source", 0, "--source", 7, "-o", tmp_path / "d.txt")
        theirs = read_numbers(tmp_path / "d.txt")
        assert np.abs(g.distance([0, 7]) - theirs).max() <= 1e-12 * theirs.max(), relative
        cli("geodesic", mesh, "--each-source", "0,7,20", "-o", tmp_path / "e.txt")
        each = g.distances_each([0, 7, 20])
        assert each.shape == (3, len(V))
        assert np.abs(each.T - fields(tmp_path / "e.txt")).max() <= 1e-12 * theirs.max()


def test_options_follow_the_command_line(tmp_path, cli):
    V2, F = grid(20, 20)
    V = bump(V2)
    bdmorph.write_obj(tmp_path / "bump.obj", V, F)
    for kwargs, flags in [
        ({"boundary": "neumann"}, ["--boundary", "neumann"]),
        ({"boundary": "average", "time_factor": 1.0}, ["--boundary", "average", "--time-factor", "1"]),
        ({"intrinsic_delaunay": False}, ["--no-intrinsic-delaunay"]),
        ({"refine": 25.0, "refine_budget": 1.0}, ["--refine", "25", "--refine-budget", "1"]),
    ]:
        g = bdmorph.HeatGeodesics(V, F, **kwargs)
        cli("geodesic", tmp_path / "bump.obj", "--source", 210, *flags, "-o", tmp_path / "d.txt")
        theirs = read_numbers(tmp_path / "d.txt")
        assert np.abs(g.distance(210) - theirs).max() <= 1e-12 * theirs.max(), kwargs


def test_geodesics_are_distances():
    V2, F = grid(30, 30)
    g = bdmorph.HeatGeodesics(V2, F)          # a planar mesh (n x 2) is a surface too
    d = g.distance([0])
    assert d[0] == 0.0
    exact = np.linalg.norm(V2 - V2[0], axis=1)
    assert np.abs(d - exact).max() < 0.05 * exact.max()
    # The nearest of several sources is the minimum of the single-source fields.
    each = g.distances_each([0, 960])
    nearest = g.distance([0, 960])
    assert np.abs(nearest - each.min(axis=0)).max() < 0.05 * exact.max()
    s = g.stats
    assert s["vertices"] == len(V2) and s["has_boundary"] is True


def test_errors():
    V2, F = grid(4, 4)
    g = bdmorph.HeatGeodesics(V2, F)
    with pytest.raises(bdmorph.Error, match="vertex 99 does not exist"):
        g.distance([99])
    with pytest.raises(bdmorph.Error, match="integers"):
        g.distance([0.5])
    with pytest.raises(bdmorph.GeodesicError, match="unknown boundary"):
        bdmorph.HeatGeodesics(V2, F, boundary="sticky")
    with pytest.raises(bdmorph.Error):
        g.distance([])
    with pytest.raises(bdmorph.MeshError, match="V has"):
        bdmorph.HeatGeodesics(V2, F + 100)
