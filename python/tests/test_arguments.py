"""Wrong arguments are refused when given (at construction, not at the first use), each
message naming the argument as the caller spelled it."""

import numpy as np
import pytest

import bdmorph
from conftest import bump, disk_picture, grid, write_png

BAD_POSITIVE = [-1, 0, float("nan"), float("inf"), -float("inf")]


@pytest.fixture(scope="module")
def plate():
    return grid(4, 2, (2.0, 1.0))


@pytest.mark.parametrize("value", BAD_POSITIVE + ["1", True])
def test_deformer_weight(plate, value):
    V, F = plate
    with pytest.raises(bdmorph.DeformError, match="^weight must be"):
        bdmorph.Deformer(V, F, weight=value)
    d = bdmorph.Deformer(V, F)
    with pytest.raises(bdmorph.DeformError, match="^weight must be"):
        d.set_weight(value)


@pytest.mark.parametrize("method", ["kvf", "arap"])
@pytest.mark.parametrize("value", [-1, -1e-9, float("nan"), float("inf")])
def test_deformer_tolerance(plate, method, value):
    V, F = plate
    with pytest.raises(bdmorph.DeformError, match="^tolerance must be a finite number >= 0"):
        bdmorph.Deformer(V, F, method, tolerance=value)


def test_deformer_other_options(plate):
    V, F = plate
    for value in (0, -1, 2.5, "3", True):
        with pytest.raises(bdmorph.DeformError, match="^iterations must be"):
            bdmorph.Deformer(V, F, "arap", iterations=value)
    for value in (0.5, float("nan"), float("inf")):
        with pytest.raises(bdmorph.DeformError, match="^max_distortion must be a finite number >= 1"):
            bdmorph.Deformer(V, F, "bounded", max_distortion=value)
    d = bdmorph.Deformer(V, F, "arap")
    for empty in ([], np.zeros(0)):
        with pytest.raises(bdmorph.DeformError, match="^pins: give at least one handle"):
            d.set_pins(empty)
    with pytest.raises(bdmorph.Error, match=f"pins: vertex {len(V)} does not exist \\(the mesh has {len(V)} vertices"):
        d.set_pins([0, len(V)])
    # The good values still work, and tolerance 0 (never stop early) is allowed.
    d = bdmorph.Deformer(V, F, "kvf", weight=10, iterations=3, tolerance=0)
    d.set_pins([0, len(V) - 1])
    assert d.drag([[0, 0], [2.1, 1.0]]).shape == (len(V), 2)


def test_morph_names_the_short_pose(plate):
    V0, F = plate
    V1 = V0 * 2
    with pytest.raises(bdmorph.MeshError) as caught:
        bdmorph.Morph(V0, V1[:-1], F)
    assert str(caught.value).startswith(f"V1 has {len(V0) - 1} vertices but V0 has {len(V0)}")
    assert "F" not in str(caught.value)
    with pytest.raises(bdmorph.MeshError, match=f"^V1 has {len(V0) + 1} vertices but V0 has"):
        bdmorph.Morph(V0, np.vstack([V1, [[9, 9]]]), F)
    for cls in (bdmorph.Blend, bdmorph.Path):
        with pytest.raises(bdmorph.MeshError,
                           match=f"^keyframe 2 has {len(V0) - 2} vertices but keyframe 0 has {len(V0)}"):
            cls([V0, V1, V1[:-2]], F)


def test_the_compiled_layer_checks_the_counts_too(plate):
    # Straight into the extension (the package's checks skipped): the same message.
    V0, F = plate
    with pytest.raises(bdmorph.MeshError, match="^V1 has .* vertices but V0 has"):
        bdmorph._bdmorph.Morph(V0, V0[:-1].copy(), F)
    with pytest.raises(bdmorph.MeshError, match="^keyframe 1 has .* vertices but keyframe 0 has"):
        bdmorph._bdmorph.Blend([V0, V0[:-1].copy()], F)
    with pytest.raises(bdmorph.DeformError, match="^weight must be"):
        bdmorph._bdmorph.Deformer(V0, F, "kvf", -1.0)
    with pytest.raises(bdmorph.DeformError, match="^tolerance must be"):
        bdmorph._bdmorph.Deformer(V0, F, "arap", None, None, None, float("nan"))
    with pytest.raises(bdmorph.GeodesicError, match="^time_factor must be"):
        bdmorph._bdmorph.HeatGeodesics(V0, F, -1.0)
    g = bdmorph._bdmorph.HeatGeodesics(V0, F)
    with pytest.raises(bdmorph.GeodesicError, match="at least one source"):
        g.distance(np.zeros(0, dtype=np.int64))


@pytest.mark.parametrize("cls", ["Morph", "Blend", "Path"])
def test_morph_options(plate, cls):
    V0, F = plate
    make = {
        "Morph": lambda **kw: bdmorph.Morph(V0, V0 * 2, F, **kw),
        "Blend": lambda **kw: bdmorph.Blend([V0, V0 * 2], F, **kw),
        "Path": lambda **kw: bdmorph.Path([V0, V0 * 2], F, **kw),
    }[cls]
    for value in BAD_POSITIVE:
        with pytest.raises(bdmorph.MorphError, match="^tolerance must be a finite number > 0"):
            make(tolerance=value)
    for value in (0, -1, 1.5, "10", True):
        with pytest.raises(bdmorph.MorphError, match="^max_iterations must be"):
            make(max_iterations=value)


def test_path_durations(plate):
    V0, F = plate
    for value in BAD_POSITIVE:
        with pytest.raises(bdmorph.MorphError, match=r"^durations\[1\] must be a finite number > 0"):
            bdmorph.Path([V0, V0 * 2, V0], F, durations=[1, value])
    with pytest.raises(bdmorph.MorphError, match="^durations must be a list"):
        bdmorph.Path([V0, V0 * 2, V0], F, durations=3)


def test_geodesic_sources_and_options(plate):
    V, F = plate
    g = bdmorph.HeatGeodesics(V, F)
    for empty in ([], (), np.zeros(0, dtype=np.int64), np.zeros(0)):
        with pytest.raises(bdmorph.GeodesicError, match="at least one source vertex"):
            g.distance(empty)
        with pytest.raises(bdmorph.GeodesicError, match="at least one source vertex"):
            g.distances_each(empty)
    with pytest.raises(bdmorph.Error, match=f"vertex {len(V)} does not exist \\(the mesh has {len(V)} vertices"):
        g.distance([0, len(V)])
    with pytest.raises(bdmorph.Error, match="vertex -1 does not exist"):
        g.distance(-1)
    for value in BAD_POSITIVE:
        with pytest.raises(bdmorph.GeodesicError, match="^time_factor must be a finite number > 0"):
            bdmorph.HeatGeodesics(V, F, time_factor=value)


def test_parameterisation_options():
    V2, F = grid(4, 4)
    V = bump(V2)
    for value in (0, -3, 2.5, True):
        with pytest.raises(bdmorph.ParamError, match="^iterations must be"):
            bdmorph.parameterize(V, F, "arap", iterations=value)
        with pytest.raises(bdmorph.ParamError, match="^iterations must be"):
            bdmorph.bounded_distortion(V, F, 2.0, iterations=value)
    for value in (-1, float("nan"), float("inf")):
        with pytest.raises(bdmorph.ParamError, match="^tolerance must be a finite number >= 0"):
            bdmorph.parameterize(V, F, "arap", tolerance=value)
        with pytest.raises(bdmorph.ParamError, match="^collapse_barrier must be a finite number >= 0"):
            bdmorph.parameterize(V, F, "arap-newton", collapse_barrier=value)
    for value in (0.5, float("nan"), float("inf"), "2"):
        with pytest.raises(bdmorph.ParamError, match="^max_distortion must be"):
            bdmorph.bounded_distortion(V, F, value)
    for pins in ([0, 1, 2], 5, "01", ([0], [[0, 0]], "extra")):
        with pytest.raises(bdmorph.ParamError, match=r"^pins must be a pair \(vertices, targets\)"):
            bdmorph.bounded_distortion(V, F, 2.0, pins=pins)


def test_meshing_options(tmp_path):
    write_png(tmp_path / "ring.png", disk_picture(60))
    picture = tmp_path / "ring.png"
    cases = [
        ({"vertices": 2}, "^vertices must be from 3 to"),
        ({"vertices": 10.5}, "^vertices must be a whole number"),
        ({"vertices": None}, "^vertices must be a whole number"),
        ({"tolerance": 0}, "^tolerance must be a finite number > 0"),
        ({"tolerance": float("nan")}, "^tolerance must be a finite number > 0"),
        ({"min_angle": 40}, "^min_angle must be a finite number >= 0 and <= 33"),
        ({"min_angle": -1}, "^min_angle must be"),
        ({"threshold": 1.0}, "^threshold must be a finite number >= 0 and < 1"),
        ({"threshold": float("nan")}, "^threshold must be"),
    ]
    for kwargs, says in cases:
        with pytest.raises(bdmorph.MeshingError, match=says):
            bdmorph.mesh_from_image(picture, **kwargs)


def test_a_frame_time_must_be_a_number(plate):
    V0, F = plate
    for make in (lambda: bdmorph.Morph(V0, V0 * 2, F), lambda: bdmorph.Path([V0, V0 * 2], F)):
        m = make()
        for bad in ("0.5", None, [0.5], True):
            with pytest.raises(bdmorph.MorphError, match="^t must be a number"):
                m.frame(bad)
        assert m.frame(np.float32(0.5)).shape == (len(V0), 2)
