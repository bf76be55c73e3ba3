"""In-betweens of two drawings from Python: the compatible mesh, and its frames as arrays."""

import numpy as np
import pytest

import bdmorph
from conftest import write_png


def capsule_picture(size: int, a, b, radius: float) -> np.ndarray:
    """An opaque capsule (segment ab, radius) on a transparent size x size picture."""
    y, x = np.mgrid[0:size, 0:size] + 0.5
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    t = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
    d = np.hypot(x - ax - t * dx, y - ay - t * dy) - radius
    rgba = np.zeros((size, size, 4), dtype=np.uint8)
    rgba[..., 0] = (255 * x / size).astype(np.uint8)
    rgba[..., 1] = 120
    rgba[..., 2] = (255 * y / size).astype(np.uint8)
    rgba[..., 3] = (255 * np.clip(0.5 - d, 0.0, 1.0)).astype(np.uint8)
    return rgba


def signed_areas(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


@pytest.fixture
def drawings(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    write_png(a, capsule_picture(120, (60, 100), (60, 25), 16))
    write_png(b, capsule_picture(120, (60, 100), (90, 35), 16))
    return a, b


def test_the_compatible_mesh_is_flip_free_over_both_drawings(drawings):
    a, b = drawings
    VA, F, VB, report = bdmorph.compatible_mesh(a, b, vertices=300)
    assert VA.shape == VB.shape and VA.shape[1] == 2 and F.shape[1] == 3
    assert (signed_areas(VA, F) > 0).all() and (signed_areas(VB, F) > 0).all()
    assert report["vertices"] == len(VA) and report["max_distortion"] >= 1.0
    assert report["outline_error"] <= report["tolerance"][1]
    frames = bdmorph.Morph(VA, VB, F).frames(np.linspace(0.0, 1.0, 9))
    assert frames.shape == (9, len(VA), 2)
    assert np.abs(frames[0] - VA).max() < 1e-8 * np.ptp(VA)
    assert np.abs(frames[-1] - VB).max() < 1e-8 * np.ptp(VB)


def test_pairs_are_reported(drawings):
    a, b = drawings
    # The capsule's top end in A becomes its top end in B (y from the top edge).
    matches = [[60.0, 9.0, 99.0, 20.0]]
    VA, F, VB, report = bdmorph.compatible_mesh(a, b, matches=matches, vertices=300)
    assert len(report["pairs"]) == 1
    pair = report["pairs"][0]
    assert pair["on_outline"] and pair["met"] and pair["reason"] is None


def test_mistakes_raise_inbetween_error(drawings, tmp_path):
    a, b = drawings
    ring = capsule_picture(120, (60, 40), (60, 80), 40)
    y, x = np.mgrid[0:120, 0:120] + 0.5
    ring[np.hypot(x - 60, y - 60) < 15, 3] = 0
    write_png(tmp_path / "ring.png", ring)
    # Holes that differ are handled: B's hole is covered by the mesh (transparent in B).
    VA, F, VB, _ = bdmorph.compatible_mesh(a, tmp_path / "ring.png", vertices=300)
    assert (signed_areas(VA, F) > 0).all() and (signed_areas(VB, F) > 0).all()
    # A different number of pieces is not.
    two = np.maximum(
        capsule_picture(120, (30, 50), (30, 70), 20), capsule_picture(120, (90, 50), (90, 70), 20)
    )
    write_png(tmp_path / "two.png", two)
    with pytest.raises(bdmorph.InbetweenError, match="1 piece and drawing B has 2 pieces"):
        bdmorph.compatible_mesh(a, tmp_path / "two.png", vertices=300)
    with pytest.raises(bdmorph.InbetweenError, match="k x 4"):
        bdmorph.compatible_mesh(a, b, matches=[[1.0, 2.0, 3.0]])
    with pytest.raises(bdmorph.InbetweenError, match="vertices"):
        bdmorph.compatible_mesh(a, b, vertices=2)
    with pytest.raises(bdmorph.InbetweenError, match="missing.png"):
        bdmorph.compatible_mesh(tmp_path / "missing.png", b)
