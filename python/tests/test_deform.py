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
                      "pin_residual", "max_distortion", "bound_met", "status"}
    assert r["bound_met"] is None and r["flipped_triangles"] == 0
    # Converged exactly when the last iteration moved no vertex by more than the tolerance.
    assert r["status"] in {"moving", "converged"}
    assert (r["status"] == "converged") == (r["last_change"] <= 1e-10)


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


def test_sd_flips_nothing_where_arap_folds(plate):
    # The plate's right corner pulled back over its left end in three quick moves: ARAP
    # (two iterations a move) folds it; symmetric Dirichlet flips no triangle at any move,
    # its report measured from the pose it returns, and settles with the handle followed.
    V, F = plate
    pins, _ = pins_of(V)
    goal = np.array([V[pins[0]], [-1.0, 1.5]])
    folds = {}
    for method, extra in [("arap", {"iterations": 2}), ("sd", {})]:
        d = bdmorph.Deformer(V, F, method, **extra)
        d.set_pins(pins)
        most = 0
        for k in range(1, 4):
            P = d.drag(V[pins] + (goal - V[pins]) * k / 3)
            most = max(most, d.report["flipped_triangles"])
            assert np.isfinite(P).all()
        folds[method] = most
        if method == "sd":
            for _ in range(200):
                P = d.drag(goal)
                if d.report["status"] == "converged":
                    break
            assert d.report["flipped_triangles"] == 0
            assert d.report["pin_residual"] < 0.05
            assert d.method == "sd"
            d.set_weight(10.0)                 # softer handles: further from their targets
            for _ in range(200):
                d.drag(goal)
            assert d.report["flipped_triangles"] == 0
    assert folds["arap"] > 0 and folds["sd"] == 0, folds


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
    with pytest.raises(bdmorph.DeformError,
                       match="only methods 'kvf' and 'sd' have a handle weight"):
        bdmorph.Deformer(V, F, "arap", weight=3.0)
    with pytest.raises(bdmorph.DeformError, match="weight must be a finite number > 0"):
        bdmorph.Deformer(V, F, "sd", weight=0.0)
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


def test_stiffness_keeps_a_painted_region_rigid_and_is_checked(plate):
    V, F = plate
    F = np.asarray(F)
    pins, targets = pins_of(V)
    centroid_x = V[F][:, :, 0].mean(axis=1)
    painted = centroid_x < 2.0
    weights = np.where(painted, 1000.0, 1.0)

    def worst_painted(P):
        # Each painted triangle's singular values against 1.
        out = 0.0
        for f in F[painted]:
            dm = np.column_stack([V[f[1]] - V[f[0]], V[f[2]] - V[f[0]]])
            ds = np.column_stack([P[f[1]] - P[f[0]], P[f[2]] - P[f[0]]])
            s = np.linalg.svd(ds @ np.linalg.inv(dm), compute_uv=False)
            out = max(out, np.abs(s - 1).max())
        return out

    for method, extra in [("kvf", {}), ("arap", {}), ("bounded", {"max_distortion": 3.0}),
                          ("sd", {})]:
        plain = bdmorph.Deformer(V, F, method, **extra)
        stiff = bdmorph.Deformer(V, F, method, stiffness=weights, **extra)
        later = bdmorph.Deformer(V, F, method, **extra)
        for d in (plain, stiff, later):
            d.set_pins(pins)
        later.set_stiffness(weights)            # after the pins: refactors
        assert np.array_equal(stiff.stiffness, weights) and plain.stiffness is None
        for k in range(1, 11):
            goal = V[pins] + (np.array(targets) - V[pins]) * k / 10
            P0, P1, P2 = plain.drag(goal), stiff.drag(goal), later.drag(goal)
        for _ in range(50):
            P1, P2 = stiff.drag(goal), later.drag(goal)
        assert np.array_equal(P1, P2), method
        assert worst_painted(P1) <= 0.01 < worst_painted(P0), method
        later.set_stiffness(None)
        assert later.stiffness is None

    d = bdmorph.Deformer(V, F, "arap")
    with pytest.raises(bdmorph.DeformError, match=f"{len(F) - 1} stiffness weights given for "
                                                  f"{len(F)} triangles"):
        d.set_stiffness(weights[1:])
    bad = weights.copy()
    bad[5] = 0.5
    with pytest.raises(bdmorph.DeformError, match="stiffness of triangle 5 .* >= 1"):
        bdmorph.Deformer(V, F, "kvf", stiffness=bad)
    bad[5] = np.nan
    with pytest.raises(bdmorph.DeformError, match="triangle 5"):
        d.set_stiffness(bad)
    with pytest.raises(bdmorph.DeformError, match="1-D array of numbers"):
        d.set_stiffness(np.ones((len(F), 1)))
    with pytest.raises(bdmorph.DeformError, match="1-D array of numbers"):
        d.set_stiffness(["stiff"] * len(F))
    assert d.stiffness is None                  # nothing changed
