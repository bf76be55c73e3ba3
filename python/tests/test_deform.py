"""Deformer against the command line's poses (`bdmorph deform --method ...`), its reports,
and its errors."""

import numpy as np
import pytest

import bdmorph
from conftest import grid


@pytest.fixture(scope="module")
def plate():
    return grid(16, 4, (4.0, 1.0))


def pins_of(V):
    left = int(np.argmin(V[:, 0] + V[:, 1]))
    right = int(np.argmax(V[:, 0] + V[:, 1]))
    return [left, right], [V[left].tolist(), [V[right][0] - 0.4, V[right][1] + 1.2]]


def write_pose_args(pins, targets):
    args = []
    for v, (x, y) in zip(pins, targets):
        args += ["--pin", f"{v}:{float(x)!r},{float(y)!r}"]
    return args


def test_arap_equals_the_command_lines(tmp_path, cli, plate):
    V, F = plate
    pins, targets = pins_of(V)
    bdmorph.write_obj(tmp_path / "p.obj", V, F)
    cli("deform", tmp_path / "p.obj", "--method", "arap", *write_pose_args(pins, targets),
        "-o", tmp_path / "out.obj")
    theirs, _ = bdmorph.read_mesh(tmp_path / "out.obj")
    d = bdmorph.Deformer(V, F, "arap", iterations=1000, tolerance=1e-10)
    d.set_pins(pins)
    ours = d.drag(targets)
    assert np.abs(ours - theirs[:, :2]).max() <= 1e-12 * 4.0
    assert np.abs(ours[pins] - targets).max() == 0.0
    r = d.report
    assert set(r) == {"iterations", "energy", "last_change", "flipped_triangles",
                      "pin_residual", "max_distortion", "bound_met"}
    assert r["bound_met"] is None and r["flipped_triangles"] == 0


def test_kvf_equals_the_command_lines(tmp_path, cli, plate):
    V, F = plate
    pins, targets = pins_of(V)
    bdmorph.write_obj(tmp_path / "p.obj", V, F)
    cli("deform", tmp_path / "p.obj", "--method", "kvf", *write_pose_args(pins, targets),
        "-o", tmp_path / "out.obj")
    theirs, _ = bdmorph.read_mesh(tmp_path / "out.obj")
    # The command line's way: ten even moves, then drags at the targets until settled.
    d = bdmorph.Deformer(V, F, "kvf")
    d.set_pins(pins)
    start, goal = V[pins], np.array(targets)
    for k in range(1, 11):
        d.drag(start + (goal - start) * k / 10)
    iterations = 0
    while iterations < 1000:
        ours = d.drag(goal)
        iterations += d.report["iterations"]
        if d.report["last_change"] <= 1e-10:
            break
    assert np.abs(ours - theirs[:, :2]).max() <= 1e-12 * 4.0
    assert d.report["pin_residual"] < 1e-2


def test_bounded_holds_its_bound_and_says_so(plate):
    V, F = plate
    pins, targets = pins_of(V)
    d = bdmorph.Deformer(V, F, "bounded", max_distortion=2.0)
    d.set_pins(pins)
    for k in range(1, 11):
        P = d.drag(V[pins] + (np.array(targets) - V[pins]) * k / 10)
    assert d.report["bound_met"] is True and d.report["max_distortion"] <= 2.0 * 1.001
    assert np.abs(P[pins] - targets).max() < 1e-9


def test_undo_reset_weight_and_layouts(plate):
    V, F = plate
    pins, targets = pins_of(V)
    d = bdmorph.Deformer(V, F)
    assert d.method == "kvf" and d.report is None
    d.set_pins(np.array(pins, dtype=np.uint16))
    first = d.drag(np.asfortranarray(np.array(targets, dtype=np.float32)))
    d.drag(np.array(targets) + [[0, 0], [0.5, 0.5]])
    d.set_positions(first)
    assert np.array_equal(d.positions, first)
    d.set_weight(1000.0)
    assert d.pins == pins
    d.reset()
    assert np.array_equal(d.positions, V)


def test_errors(plate):
    V, F = plate
    with pytest.raises(bdmorph.DeformError, match="unknown method 'spring'"):
        bdmorph.Deformer(V, F, "spring")
    with pytest.raises(bdmorph.DeformError, match="needs max_distortion"):
        bdmorph.Deformer(V, F, "bounded")
    with pytest.raises(bdmorph.DeformError, match="only method 'kvf' has a handle weight"):
        bdmorph.Deformer(V, F, "arap", weight=3.0)
    with pytest.raises(bdmorph.DeformError):
        bdmorph.Deformer(V, F, "bounded", max_distortion=0.5)
    d = bdmorph.Deformer(V, F, "arap")
    with pytest.raises(bdmorph.Error, match="vertex 999 does not exist"):
        d.set_pins([0, 999])
    with pytest.raises(bdmorph.DeformError):
        d.set_pins([0, 0])
    with pytest.raises(bdmorph.DeformError):
        d.drag([[0, 0]])                      # no pins yet
    d.set_pins([0, 5])
    with pytest.raises(bdmorph.DeformError):
        d.drag([[0, 0]])                      # one target for two pins
    with pytest.raises(bdmorph.DeformError):
        d.drag([[0, 0], [np.inf, 0]])
    with pytest.raises(bdmorph.DeformError, match="weight"):
        bdmorph.Deformer(V, F).set_weight(-1)
