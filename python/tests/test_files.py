"""read_mesh / write_obj round trips, mesh_from_image against `bdmorph mesh`, and file
errors."""

import numpy as np
import pytest

import bdmorph
from conftest import bump, disk_picture, grid, shared, write_png


def test_round_trips_are_bit_exact(tmp_path):
    V2, F = grid(5, 4)
    rng = np.random.default_rng(7)
    V2 = V2 + rng.normal(scale=1e-3, size=V2.shape) * [1, 1e-9]   # digits that must survive
    bdmorph.write_obj(tmp_path / "flat.obj", V2, F)
    V, G = bdmorph.read_mesh(tmp_path / "flat.obj")
    assert V.shape == (len(V2), 3) and V.dtype == np.float64 and G.dtype == np.int64
    assert np.array_equal(V[:, :2], V2) and np.array_equal(G, F) and not V[:, 2].any()
    V3 = bump(V2, 1e-7) + [1e20, -3e-300, 0]
    bdmorph.write_obj(tmp_path / "space.obj", V3, F)
    back, _ = bdmorph.read_mesh(tmp_path / "space.obj")
    assert np.array_equal(back, V3)


def test_a_shared_mesh_reads_as_the_library_does():
    V, F = bdmorph.read_mesh(shared("closed3d/libigl/bunny.off"))
    assert V.shape == (3485, 3) and F.shape[1] == 3 and F.min() == 0 and F.max() == 3484


def test_file_errors(tmp_path):
    with pytest.raises(bdmorph.FileError, match="nothing.obj"):
        bdmorph.read_mesh(tmp_path / "nothing.obj")
    (tmp_path / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    with pytest.raises(bdmorph.FileError, match="quad.obj"):
        bdmorph.read_mesh(tmp_path / "quad.obj")
    V2, F = grid(2, 2)
    with pytest.raises(bdmorph.FileError):
        bdmorph.write_obj(tmp_path / "no" / "such" / "dir.obj", V2, F)
    bad = V2.copy()
    bad[0, 0] = np.nan
    with pytest.raises(bdmorph.FileError, match="not finite"):
        bdmorph.write_obj(tmp_path / "nan.obj", bad, F)
    assert not (tmp_path / "nan.obj").exists()


def test_mesh_from_image_equals_the_command_lines(tmp_path, cli):
    write_png(tmp_path / "ring.png", disk_picture(160))
    V, F = bdmorph.mesh_from_image(tmp_path / "ring.png", vertices=600)
    cli("mesh", tmp_path / "ring.png", "--vertices", 600, "-o", tmp_path / "ring.obj")
    theirs, their_faces = bdmorph.read_mesh(tmp_path / "ring.obj")
    assert np.array_equal(V, theirs[:, :2]) and np.array_equal(F, their_faces)
    assert 400 < len(V) < 800
    # In the picture's pixels, y up: nothing in the hole, nothing outside the disk.
    r = np.hypot(V[:, 0] - 80, V[:, 1] - 80)
    assert r.max() < 65 and np.abs(V - 80).max(axis=1).min() > 15
    # Ready to pose and morph.
    d = bdmorph.Deformer(V, F, "arap")
    d.set_pins([0, 1])
    d.drag(V[[0, 1]] + [[0, 0], [3, 2]])
    assert d.report["flipped_triangles"] == 0


def test_meshing_errors(tmp_path):
    with pytest.raises(bdmorph.MeshingError, match="missing.png"):
        bdmorph.mesh_from_image(tmp_path / "missing.png")
    empty = np.zeros((40, 40, 4), dtype=np.uint8)
    write_png(tmp_path / "empty.png", empty)
    with pytest.raises(bdmorph.MeshingError):
        bdmorph.mesh_from_image(tmp_path / "empty.png")
    write_png(tmp_path / "ring.png", disk_picture(80))
    with pytest.raises(bdmorph.MeshingError, match="vertices"):
        bdmorph.mesh_from_image(tmp_path / "ring.png", vertices=1)
