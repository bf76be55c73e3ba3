"""Every public name documents itself, and the typical use the type checker checks in CI
(typing_usage.py) runs as written."""

import inspect

import pytest

import bdmorph
import typing_usage
from conftest import disk_picture, write_png


def public_members(obj):
    for name, member in inspect.getmembers(obj):
        if name.startswith("_"):
            continue
        # What a class inherits from object, tuple (NamedTuple) or an exception is not ours.
        if inspect.isclass(obj) and not any(name in vars(k) for k in obj.__mro__
                                            if k.__module__ == "bdmorph"):
            continue
        yield name, member


def test_every_public_name_has_a_docstring():
    missing = []
    checked = 0
    for name in bdmorph.__all__:
        obj = getattr(bdmorph, name)
        checked += 1
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            for member_name, _ in public_members(obj):
                raw = inspect.getattr_static(obj, member_name)
                doc = getattr(raw, "__doc__", None) or getattr(getattr(raw, "fget", None), "__doc__", None)
                checked += 1
                if isinstance(raw, (int, float, str)) or not (doc or "").strip():
                    missing.append(f"{name}.{member_name}")
    assert not missing, f"no docstring: {missing}"
    assert checked > 50
    # The batch's on_error is documented where it is accepted.
    for cls in (bdmorph.Morph, bdmorph.Blend, bdmorph.Path):
        assert "on_error" in cls.frames.__doc__ and "failures" in cls.frames.__doc__


def test_the_typed_usage_runs(tmp_path):
    write_png(tmp_path / "ring.png", disk_picture(80))
    seen = typing_usage.main(tmp_path / "ring.png", tmp_path)
    assert "frame (9, 2)" in seen
    assert "frames (5, 9, 2), flipped 0" in seen
    assert "failed ts[2] = nan: MorphError" in seen and "nan frames 1" in seen
    assert "raised ts[1]" in seen
    assert "uv (9, 2)" in seen and "bounded (9, 2)" in seen
    assert "picture mesh 2 3" in seen
    assert "read back (9, 3) (8, 3)" in seen
    assert any(line.startswith("refused: weight must be") for line in seen), seen


def test_the_overloads_decide_the_result_by_full_output():
    import typing

    hints = [typing.get_type_hints(f) for f in typing.get_overloads(bdmorph.parameterize)] \
        if hasattr(typing, "get_overloads") else []
    if not hints:
        pytest.skip("typing.get_overloads needs Python 3.11")
    assert len(hints) == 3
    assert len(typing.get_overloads(bdmorph.bounded_distortion)) == 3
