"""parameterize and bounded_distortion against the command line's maps, their reports and
warnings (the command line's words), and errors."""

import warnings

import numpy as np
import pytest

import bdmorph
from conftest import bump, grid, read_vt, shared


@pytest.fixture(scope="module")
def surface():
    V2, F = grid(16, 12)
    return bump(V2, 0.4), F


@pytest.mark.parametrize("method", ["tutte", "lscm", "asap", "arap", "sd", "mips", "arap-newton"])
def test_every_method_equals_the_command_lines(tmp_path, cli, surface, method):
    V, F = surface
    bdmorph.write_obj(tmp_path / "s.obj", V, F)
    cli("param", tmp_path / "s.obj", "--method", method, "--iterations", 20, "-o", tmp_path / "uv.obj")
    UV, info = bdmorph.parameterize(V, F, method, iterations=20, full_output=True)
    theirs = read_vt(tmp_path / "uv.obj")
    assert UV.shape == (len(V), 2)
    assert np.abs(UV - theirs).max() <= 1e-12 * np.ptp(theirs, axis=0).max(), method
    assert info["flipped"] == 0 and info["message"] is None
    assert info["stop"] in {"direct", "converged", "iteration-limit"}


def test_a_shared_disk_flattens_as_the_command_line_does(tmp_path, cli):
    mesh = shared("disk3d/ustc-cg/Cat_head.obj")
    V, F = bdmorph.read_mesh(mesh)
    cli("param", mesh, "--method", "sd", "-o", tmp_path / "uv.obj")
    UV = bdmorph.parameterize(V, F, "sd")
    theirs = read_vt(tmp_path / "uv.obj")
    assert np.abs(UV - theirs).max() <= 1e-12 * np.ptp(theirs, axis=0).max()


def test_bounded_distortion_meets_the_bound_as_the_command_line(tmp_path, cli, surface):
    V, F = surface
    bdmorph.write_obj(tmp_path / "s.obj", V, F)
    cli("param", tmp_path / "s.obj", "--method", "bounded", "--max-distortion", 1.5,
        "-o", tmp_path / "uv.obj")
    UV, info = bdmorph.bounded_distortion(V, F, 1.5, full_output=True)
    theirs = read_vt(tmp_path / "uv.obj")
    assert np.abs(UV - theirs).max() <= 1e-12 * np.ptp(theirs, axis=0).max()
    assert info["converged"] and info["max_distortion"] <= 1.5 * (1 + 1e-3)
    assert info["inverted"] == 0 and not info["infeasible"] and info["message"] is None
    # With pins (two corners where the unpinned map puts them, turned by 90 degrees: the map
    # turned meets them): the pinned vertices land on their targets and the bound holds.
    corners = [0, 16]
    targets = UV[corners] @ np.array([[0.0, 1.0], [-1.0, 0.0]])
    pinned, info = bdmorph.bounded_distortion(V, F, 1.5, pins=(corners, targets),
                                              full_output=True)
    assert np.abs(pinned[corners] - targets).max() < 1e-9
    assert info["converged"] and info["max_distortion"] <= 1.5 * (1 + 1e-3)
    # The whole boundary pinned to the map stretched threefold along u (an affine map of
    # distortion 3, which no map within 1.5 matches): returned, with a warning saying why.
    V2 = grid(16, 12)[0]
    rim = np.flatnonzero((V2 == 0).any(axis=1) | (V2 == 1).any(axis=1))
    with pytest.warns(bdmorph.SolverWarning, match="the distortion bound 1.5 was not met"):
        far, info = bdmorph.bounded_distortion(V, F, 1.5, pins=(rim, UV[rim] * [3.0, 1.0]),
                                               iterations=200, full_output=True)
    assert not info["converged"] and far.shape == UV.shape


def test_an_infeasible_bound_warns_in_the_command_lines_words(tmp_path, cli):
    # A cone: its apex's angle sum is far from 2 pi, so K = 1.05 cannot be met.
    n = 12
    ring = [[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, n, endpoint=False)]
    V = np.array([[0.0, 0.0, 1.5]] + ring)
    F = np.array([[0, 1 + i, 1 + (i + 1) % n] for i in range(n)])
    bdmorph.write_obj(tmp_path / "cone.obj", V, F)
    with pytest.warns(bdmorph.SolverWarning) as caught:
        UV, info = bdmorph.bounded_distortion(V, F, 1.05, full_output=True)
    ours = str(caught[0].message)
    assert not info["converged"] and info["infeasible"]
    assert ours.startswith("the distortion bound 1.05 is infeasible for this mesh")
    done = cli("param", tmp_path / "cone.obj", "--method", "bounded", "--max-distortion", 1.05,
               "-o", tmp_path / "uv.obj", check=False)
    # The same sentence, up to where the command line names the file's lines.
    assert ours.split(";")[0] in done.stderr, done.stderr


def test_no_warning_when_all_is_well(surface):
    V, F = surface
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bdmorph.parameterize(V, F, "lscm")


def test_errors(surface):
    V, F = surface
    with pytest.raises(bdmorph.ParamError, match="unknown method 'conformal'"):
        bdmorph.parameterize(V, F, "conformal")
    with pytest.raises(bdmorph.ParamError, match="tolerance"):
        bdmorph.parameterize(V, F, "arap", tolerance=-1.0)
    with pytest.raises(bdmorph.ParamError):
        bdmorph.bounded_distortion(V, F, 0.5)
    with pytest.raises(bdmorph.ParamError, match="unknown start"):
        bdmorph.bounded_distortion(V, F, 2.0, init="random")
    with pytest.raises(bdmorph.ParamError, match="2 pinned vertices but 1 targets"):
        bdmorph.bounded_distortion(V, F, 2.0, pins=([0, 1], [[0, 0]]))
    # A closed surface is not a disk.
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
    with pytest.raises(bdmorph.ParamError, match="not a disk"):
        bdmorph.parameterize(tetra, faces, "arap")
