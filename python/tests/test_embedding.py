"""The package embedded in other programs: its exceptions pickle by name (so that an error in a
`multiprocessing` / `concurrent.futures` worker reaches the parent as itself, its message
intact)."""

import concurrent.futures
import multiprocessing
import pickle

import numpy as np
import pytest

import bdmorph
from conftest import grid

EXCEPTIONS = [bdmorph.Error, bdmorph.MeshError, bdmorph.MorphError, bdmorph.GeodesicError,
              bdmorph.ParamError, bdmorph.DeformError, bdmorph.MeshingError, bdmorph.FileError,
              bdmorph.InbetweenError]


def test_the_exceptions_live_in_the_public_module_and_keep_their_hierarchy():
    assert issubclass(bdmorph.Error, ValueError)
    for cls in EXCEPTIONS:
        assert cls.__module__ == "bdmorph", cls
        assert getattr(bdmorph, cls.__name__) is cls
        assert cls.__doc__
        if cls is not bdmorph.Error:
            assert cls.__bases__ == (bdmorph.Error,), cls


@pytest.mark.parametrize("cls", EXCEPTIONS, ids=lambda c: c.__name__)
def test_every_exception_pickles_to_itself(cls):
    e = cls("V1 has 3 vertices but V0 has 4: 'quoted', \u00e9")
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        back = pickle.loads(pickle.dumps(e, protocol=protocol))
        assert type(back) is cls
        assert str(back) == str(e) and back.args == e.args


def test_an_error_raised_by_the_engine_pickles_to_itself():
    V0, F = grid(3, 2)
    with pytest.raises(bdmorph.MorphError) as caught:
        bdmorph.Morph(V0, V0 * 2, F).frame(float("nan"))
    back = pickle.loads(pickle.dumps(caught.value))
    assert type(back) is bdmorph.MorphError
    assert str(back) == str(caught.value) and "not a finite number" in str(back)


def frames_in_a_worker(V0, V1, F, ts):
    """Run in a worker process: the frames at `ts` (an error propagates to the parent)."""
    return bdmorph.Morph(V0, V1, F).frames(ts)


@pytest.mark.parametrize("method", ["spawn", "fork"])
def test_errors_cross_a_process_pool_as_themselves(method):
    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method} start method here")
    V0, F = grid(4, 2, (2.0, 1.0))
    V1 = V0 * [1.0, 1.5]
    context = multiprocessing.get_context(method)
    with concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=context) as pool:
        # A good call first: the worker imports bdmorph and returns the frames.
        good = pool.submit(frames_in_a_worker, V0, V1, F, [0.0, 1.0]).result(timeout=120)
        assert good.shape == (2, len(V0), 2)
        # An error raised by the compiled engine in the worker: a MorphError here.
        bad = pool.submit(frames_in_a_worker, V0, V1, F, [0.0, float("nan")])
        with pytest.raises(bdmorph.MorphError) as caught:
            bad.result(timeout=120)
        assert str(caught.value).startswith("ts[1]: ") and "not a finite number" in str(caught.value)
        # A shape error from the package's own checks (the class itself is the task).
        short = pool.submit(bdmorph.Morph, V0, V1[:-1], F)
        with pytest.raises(bdmorph.MeshError, match=f"V1 has {len(V0) - 1} vertices but V0 has {len(V0)}"):
            short.result(timeout=120)
        # And one from inside the engine's mesh checks: a clockwise triangle.
        flipped = F.copy()
        flipped[0] = flipped[0][::-1]
        inverted = pool.submit(bdmorph.Morph, V0, V1, flipped)
        with pytest.raises(bdmorph.MeshError, match="V0: "):
            inverted.result(timeout=120)
