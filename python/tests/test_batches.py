"""Batches of frames (`frames`) with a frame that cannot be computed: `on_error="raise"` names
it, `on_error="nan"` returns the others and lists the failures."""

import numpy as np
import pytest

import bdmorph
from conftest import bend, grid


@pytest.fixture(scope="module")
def strip():
    V0, F = grid(8, 2, (4.0, 1.0))
    return V0, bend(V0, 1.0), F


def test_morph_raise_names_the_frame_and_returns_none(strip):
    V0, V1, F = strip
    m = bdmorph.Morph(V0, V1, F)
    with pytest.raises(bdmorph.MorphError) as caught:
        m.frames([0.0, 0.5, float("nan"), 1.0])
    assert str(caught.value).startswith("ts[2]: t = NaN is not a finite number"), str(caught.value)
    with pytest.raises(bdmorph.MorphError, match="on_error must be 'raise' or 'nan', not 'skip'"):
        m.frames([0.0], on_error="skip")


def test_morph_nan_keeps_the_good_frames(strip):
    V0, V1, F = strip
    ts = [0.0, 0.5, float("inf"), 1.0, float("nan")]
    m = bdmorph.Morph(V0, V1, F)
    got = m.frames(ts, on_error="nan")
    assert got.shape == (5, len(V0), 2)
    assert [(f.index, type(f.error)) for f in m.failures] == [(2, bdmorph.MorphError),
                                                              (4, bdmorph.MorphError)]
    assert m.failures[0].at == float("inf") and np.isnan(m.failures[1].at)
    assert "not a finite number" in str(m.failures[0].error)
    assert np.isnan(got[[2, 4]]).all()
    # The good frames are those of a batch without the bad ones (to the solver's tolerance).
    want = bdmorph.Morph(V0, V1, F).frames([0.0, 0.5, 1.0])
    assert np.abs(got[[0, 1, 3]] - want).max() < 1e-8
    assert m.stats["t"] == 1.0                # the last good frame's
    # A later good batch clears the failures.
    m.frames([0.25], on_error="nan")
    assert m.failures == []


def test_morph_past_the_extrapolation_limit(strip):
    V0, V1, F = strip
    m = bdmorph.Morph(V0, V1, F)
    # Far past 1 the extrapolated edge lengths break a triangle inequality.
    far = 1e6
    with pytest.raises(bdmorph.MorphError) as caught:
        m.frames([0.0, far])
    assert str(caught.value).startswith("ts[1]: ")
    got = m.frames([0.0, far, 1.0], on_error="nan")
    assert [f.index for f in m.failures] == [1]
    assert np.isfinite(got[[0, 2]]).all() and np.isnan(got[1]).all()


def test_path_batches(strip):
    V0, V1, F = strip
    p = bdmorph.Path([V0, V1, V0], F)
    with pytest.raises(bdmorph.MorphError, match=r"^ts\[1\]: t = 1.3 is outside"):
        p.frames([0.0, 1.3])
    got = p.frames([0.0, 1.3, 0.5], on_error="nan")
    assert [(f.index, f.at) for f in p.failures] == [(1, 1.3)]
    assert np.isnan(got[1]).all()
    assert np.allclose(got[2], bdmorph.Path([V0, V1, V0], F).frame(0.5), atol=1e-8)


def test_blend_batches(strip):
    V0, V1, F = strip
    b = bdmorph.Blend([V0, V1], F)
    w = [[1.0, 0.0], [0.7, 0.7], [0.5, 0.5]]
    with pytest.raises(bdmorph.MorphError, match=r"^weights row 1: .*sum to 1"):
        b.frames(w)
    got = b.frames(w, on_error="nan")
    assert [(f.index, f.at) for f in b.failures] == [(1, (0.7, 0.7))]
    assert np.isnan(got[1]).all() and np.isfinite(got[[0, 2]]).all()
    assert np.allclose(got[2], bdmorph.Blend([V0, V1], F).frame([0.5, 0.5]), atol=1e-8)
