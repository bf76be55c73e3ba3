"""Morph, Blend and Path against the command line's frames (to 1e-12 of the mesh's size),
their options and errors, array layouts, many frames, and the GIL released while solving."""

import threading
import time

import numpy as np
import pytest

import bdmorph
from conftest import bend, grid, shared


@pytest.fixture(scope="module")
def strip():
    V0, F = grid(12, 3, (4.0, 1.0))
    return V0, bend(V0, 1.2), bend(V0, -0.8), F


def size_of(V):
    return float(np.ptp(V, axis=0).max())


def test_frames_equal_the_command_lines(tmp_path, cli, strip):
    V0, V1, _, F = strip
    bdmorph.write_obj(tmp_path / "a.obj", V0, F)
    bdmorph.write_obj(tmp_path / "b.obj", V1, F)
    cli("morph", tmp_path / "a.obj", tmp_path / "b.obj", "--frames", 7, "-o", tmp_path / "out")
    ours = bdmorph.Morph(V0, V1, F).frames(np.linspace(0, 1, 7))
    for i in range(7):
        theirs, faces = bdmorph.read_mesh(tmp_path / "out" / f"frame_{i:04}.obj")
        assert np.array_equal(faces, F)
        assert np.abs(ours[i] - theirs[:, :2]).max() <= 1e-12 * size_of(V0), i


def test_fit_placement_equals_the_command_lines(tmp_path, cli, strip):
    V0, V1, V2, F = strip
    for name, V in [("a", V0), ("b", V1), ("c", V2)]:
        bdmorph.write_obj(tmp_path / f"{name}.obj", V, F)
    cli("morph", *(tmp_path / f"{n}.obj" for n in "abc"), "--frames", 9, "--placement", "fit",
        "-o", tmp_path / "out")
    path = bdmorph.Path([V0, V1, V2], F, placement="fit")
    anchored = bdmorph.Path([V0, V1, V2], F)
    for i, t in enumerate(np.linspace(0, 1, 9)):
        theirs, _ = bdmorph.read_mesh(tmp_path / "out" / f"frame_{i:04}.obj")
        assert np.abs(path.frame(t) - theirs[:, :2]).max() <= 1e-12 * size_of(V0)
        # Keyframes are reached either way; in between the placements differ.
        if i % 4 == 0:
            assert np.abs(anchored.frame(t) - theirs[:, :2]).max() <= 1e-9 * size_of(V0)
    assert np.abs(bdmorph.Morph(V0, V1, F, placement="fit").frame(1.0) - V1).max() <= 1e-9
    with pytest.raises(bdmorph.MorphError, match="placement must be 'anchor' or 'fit'"):
        bdmorph.Blend([V0, V1], F, placement="wobble")


def test_extrapolation_equals_the_command_lines(tmp_path, cli, strip):
    V0, V1, _, F = strip
    bdmorph.write_obj(tmp_path / "a.obj", V0, F)
    bdmorph.write_obj(tmp_path / "b.obj", V1, F)
    cli("morph", tmp_path / "a.obj", tmp_path / "b.obj", "--t", 1.1, "-o", tmp_path / "x.obj")
    theirs, _ = bdmorph.read_mesh(tmp_path / "x.obj")
    ours = bdmorph.Morph(V0, V1, F).frame(1.1)
    assert np.abs(ours - theirs[:, :2]).max() <= 1e-12 * size_of(V0)


def test_a_path_equals_the_command_lines(tmp_path, cli, strip):
    V0, V1, V2, F = strip
    for name, V in [("a", V0), ("b", V1), ("c", V2)]:
        bdmorph.write_obj(tmp_path / f"{name}.obj", V, F)
    cli("morph", *(tmp_path / f"{n}.obj" for n in "abc"), "--frames", 9, "--durations", "1,3",
        "--easing", "ease-in-out", "-o", tmp_path / "out")
    path = bdmorph.Path([V0, V1, V2], F, durations=[1, 3], easings="ease-in-out")
    assert path.keyframe_times == [0.0, 0.25, 1.0]
    for i, t in enumerate(np.linspace(0, 1, 9)):
        theirs, _ = bdmorph.read_mesh(tmp_path / "out" / f"frame_{i:04}.obj")
        assert np.abs(path.frame(t) - theirs[:, :2]).max() <= 1e-12 * size_of(V0)


def test_a_blend_equals_the_command_lines(tmp_path, cli, strip):
    V0, V1, V2, F = strip
    for name, V in [("a", V0), ("b", V1), ("c", V2)]:
        bdmorph.write_obj(tmp_path / f"{name}.obj", V, F)
    cli("blend", *(tmp_path / f"{n}.obj" for n in "abc"), "--weights", "0.2,0.3,0.5",
        "-o", tmp_path / "mix.obj")
    theirs, _ = bdmorph.read_mesh(tmp_path / "mix.obj")
    blend = bdmorph.Blend([V0, V1, V2], F)
    assert np.abs(blend.frame([0.2, 0.3, 0.5]) - theirs[:, :2]).max() <= 1e-12 * size_of(V0)
    many = blend.frames([[1, 0, 0], [0.2, 0.3, 0.5]])
    assert many.shape == (2, len(V0), 2)
    assert np.abs(many[1] - theirs[:, :2]).max() <= 1e-12 * size_of(V0)


def test_the_shared_figure_morphs_as_the_command_line_does(tmp_path, cli):
    a, b = shared("morph2d/isadorable-man/man.obj"), shared("morph2d/isadorable-man/man2.obj")
    cli("morph", a, b, "--t", 0.3, "-o", tmp_path / "f.obj")
    (V0, F), (V1, F1) = bdmorph.read_mesh(a), bdmorph.read_mesh(b)
    theirs, _ = bdmorph.read_mesh(tmp_path / "f.obj")
    ours = bdmorph.Morph(V0, V1, F).frame(0.3)
    assert np.abs(ours - theirs[:, :2]).max() <= 1e-12 * size_of(V0[:, :2])


def test_ends_stats_and_a_many_frames_loop(strip):
    V0, V1, _, F = strip
    m = bdmorph.Morph(V0, V1, F)
    assert m.stats is None
    start = m.frame(0.0)
    # The ends are the keyframes' shapes, placed by the morph (a rigid motion away).
    assert np.allclose(np.linalg.norm(start[F[:, 1]] - start[F[:, 0]], axis=1),
                       np.linalg.norm(V0[F[:, 1]] - V0[F[:, 0]], axis=1), atol=1e-9)
    s = m.stats
    assert set(s) == {"t", "newton_iterations", "factorizations", "cg_iterations",
                      "gradient_norm", "flipped_triangles", "max_conformal_distortion", "seconds"}
    assert s["t"] == 0.0 and s["flipped_triangles"] == 0
    ts = np.linspace(0, 1, 201)
    one_by_one = np.stack([m.frame(t) for t in ts])
    batch = bdmorph.Morph(V0, V1, F).frames(ts)
    assert np.abs(one_by_one - batch).max() <= 1e-12 * size_of(V0)
    assert m.distortion.shape == (len(F),) and m.distortion.max() >= 1.0


def test_array_layouts_give_the_same_frames(strip):
    V0, V1, _, F = strip
    want = bdmorph.Morph(V0, V1, F).frame(0.4)
    V3 = np.column_stack([V0, np.zeros(len(V0))])
    layouts = [
        (np.asfortranarray(V0), np.asfortranarray(V1), np.asfortranarray(F)),
        (V0, V1, F.astype(np.int32)),
        (V0, V1, F.astype(np.uint32)),
        (V0.tolist(), V1.tolist(), F.tolist()),
        (V3, V1, F),                       # n x 3 with z = 0
        (V3[:, :2], V1, F),                # a non-contiguous view
        (V0[::-1][::-1], V1, F[:, [0, 1, 2]]),
    ]
    for a, b, f in layouts:
        assert np.array_equal(bdmorph.Morph(a, b, f).frame(0.4), want)
    # float32 input is converted (its values rounded to float32 first). The shape is the
    # same to float32's precision; its placement may differ: rounding breaks the regular
    # grid's ties in the choice of the anchor edge, which places the frame.
    got = bdmorph.Morph(V0.astype(np.float32), V1.astype(np.float32), F).frame(0.4)

    def edges(X):
        return np.linalg.norm(X[F[:, 1]] - X[F[:, 0]], axis=1)

    assert np.abs(edges(got) - edges(want)).max() < 1e-6 * size_of(V0)


def test_bad_inputs_are_refused_with_the_reason(tmp_path, cli, strip):
    V0, V1, _, F = strip
    assert issubclass(bdmorph.Error, ValueError)
    for cls in (bdmorph.MeshError, bdmorph.MorphError, bdmorph.GeodesicError,
                bdmorph.ParamError, bdmorph.DeformError, bdmorph.MeshingError, bdmorph.FileError):
        assert issubclass(cls, bdmorph.Error)
    cases = [
        ((np.zeros((4, 4)), V1, F), bdmorph.MeshError, "n x 2 or n x 3"),
        ((V0, V1, F[:, :2]), bdmorph.MeshError, "m x 3"),
        ((V0, V1, F.astype(float)), bdmorph.MeshError, "integers"),
        ((V0.astype(str), V1, F), bdmorph.MeshError, "numbers"),
        ((V0, V1, F + len(V0)), bdmorph.MeshError, "V has"),
        ((V0, V1, -F), bdmorph.MeshError, "vertex -"),
        ((V0, V1[:-1], F[:-3]), bdmorph.MeshError, "^V1 has .* vertices but V0 has"),
        ((np.column_stack([V0, np.ones(len(V0))]), V1, F), bdmorph.MeshError, "z = 1"),
    ]
    for args, error, says in cases:
        with pytest.raises(error, match=says):
            bdmorph.Morph(*args)
    nan = V0.copy()
    nan[3, 0] = np.nan
    with pytest.raises(bdmorph.MeshError):
        bdmorph.Morph(nan, V1, F)
    m = bdmorph.Morph(V0, V1, F)
    with pytest.raises(bdmorph.MorphError, match="not a finite number"):
        m.frame(float("nan"))
    with pytest.raises(bdmorph.MorphError, match="tolerance"):
        bdmorph.Morph(V0, V1, F, tolerance=-1)
    with pytest.raises(bdmorph.MorphError, match="sum to 1"):
        bdmorph.Blend([V0, V1], F).frame([0.5, 0.6])
    with pytest.raises(bdmorph.MorphError, match="weights"):
        bdmorph.Blend([V0, V1], F).frame([1.0])
    with pytest.raises(bdmorph.MorphError):
        bdmorph.Path([V0, V1, V1], F, easings=["linear", "bouncy"])
    with pytest.raises(bdmorph.MorphError):
        bdmorph.Path([V0, V1, V1], F, durations=[1])
    with pytest.raises(bdmorph.MorphError, match="at least two"):
        bdmorph.Path([V0], F)
    with pytest.raises(bdmorph.MorphError, match="outside"):
        bdmorph.Path([V0, V1, V1], F).frame(1.5)
    # A clockwise triangle: the command line's message, which names the file where we name
    # the argument.
    flipped = F.copy()
    flipped[5] = flipped[5][::-1]
    with pytest.raises(bdmorph.MeshError) as caught:
        bdmorph.Morph(V0, V1, flipped)
    ours = str(caught.value)
    assert ours.startswith("V0: ")
    bdmorph.write_obj(tmp_path / "a.obj", V0, flipped)
    bdmorph.write_obj(tmp_path / "b.obj", V1, flipped)
    done = cli("morph", tmp_path / "a.obj", tmp_path / "b.obj", "--t", 0.5, "-o",
               tmp_path / "x.obj", check=False)
    assert done.returncode != 0
    core = ours[len("V0: "):]
    assert core.split(" (")[0] in done.stderr, (core, done.stderr)


def test_the_gil_is_released_while_frames_are_computed(strip):
    V0, F = grid(60, 40, (3.0, 2.0))
    m = bdmorph.Morph(V0, bend(V0, 1.0), F)
    m.frame(0.0)
    ticks = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1

    worker = threading.Thread(target=count)
    worker.start()
    try:
        before = ticks[0]
        started = time.perf_counter()
        m.frames(np.linspace(0, 1, 40))
        elapsed = time.perf_counter() - started
        during = ticks[0] - before
    finally:
        done.set()
        worker.join()
    # With the GIL held, the counting thread would not run at all during the call (Python
    # switches threads only between bytecodes of the thread holding the GIL).
    assert elapsed > 0.01
    assert during > 1000, f"{during} ticks in {elapsed:.3f} s"


def test_the_package_documents_itself():
    import doctest

    failed, attempted = doctest.testmod(bdmorph, verbose=False)
    assert attempted > 30 and failed == 0
    for name in bdmorph.__all__:
        assert getattr(bdmorph, name).__doc__, name


def test_threads_agree_repeat_and_are_checked():
    # 161 x 51 vertices (16,000 triangles): large enough for a frame to be split over two
    # threads; a frame from one thread and from two agree within 1e-9 of the size, and two
    # threads give the same bits every time.
    V0, F = grid(160, 50, (16.0, 5.0))
    V1 = bend(V0, 2.0)
    ts = np.linspace(0, 1, 6)
    one = bdmorph.Morph(V0, V1, F, threads=1)
    assert one.threads == 1
    first = one.frames(ts)
    two = bdmorph.Morph(V0, V1, F, threads=2)
    assert two.threads == 2
    second = two.frames(ts)
    assert np.abs(first - second).max() <= 1e-9 * size_of(V0)
    assert np.array_equal(second, bdmorph.Morph(V0, V1, F, threads=2).frames(ts))
    for keys in (bdmorph.Path([V0, V1, V0], F, threads=2), bdmorph.Blend([V0, V1], F, threads=2)):
        assert keys.threads == 2
    tri = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
    assert bdmorph.Morph(tri, tri * 2, [[0, 1, 2]], threads=None).threads >= 1
    for bad in (0, 1025, -1, 2.5, "2", True):
        with pytest.raises(bdmorph.MorphError, match="threads"):
            bdmorph.Morph(V0, V1, F, threads=bad)


def test_messages_name_the_python_keyword_not_the_rust_option():
    V = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], dtype=float)
    F = np.array([[0, 1, 4], [1, 2, 4], [2, 4, 3], [3, 0, 4]])
    with pytest.raises(bdmorph.MeshError) as caught:
        bdmorph.Morph(V, V * 1.1, F)
    message = str(caught.value)
    assert "clockwise" in message
    assert "allow_inverted=True" in message
    assert "MorphOptions" not in message and "--allow-inverted" not in message
