"""bdmorph: bounded-distortion planar shape interpolation (BDMORPH), heat-method geodesics,
parameterisation and posing by handles, on a compiled Rust engine.

Arrays follow potpourri3d / libigl conventions: ``V`` is an ``n x 2`` or ``n x 3`` array of
vertex positions, ``F`` an ``m x 3`` array of vertex indices (numbered from 0). Any numeric
dtype and memory order is accepted for ``V`` (converted to C-ordered float64) and any integer
dtype for ``F`` (converted to int64); anything else is refused with a :class:`MeshError`.
Results are new float64 NumPy arrays. Every solve releases the GIL.

>>> import numpy as np, bdmorph
>>> V0 = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
>>> F = np.array([[0, 1, 2], [0, 2, 3]])
>>> V1 = V0 @ np.array([[0, 1], [-1, 0]])      # the square turned by 90 degrees
>>> m = bdmorph.Morph(V0, V1, F)
>>> m.frame(0.5).shape
(4, 2)
>>> m.stats["flipped_triangles"]
0
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Dict, List, Literal, Optional, Sequence, Tuple, Type, Union, overload

import numpy as np

from . import _bdmorph as _native
from ._bdmorph import (
    DeformError,
    Error,
    FileError,
    GeodesicError,
    InbetweenError,
    MeshError,
    MeshingError,
    MorphError,
    ParamError,
)

__version__ = _native.__version__

__all__ = [
    "Morph",
    "Blend",
    "Path",
    "HeatGeodesics",
    "ExactGeodesics",
    "geodesic_distance",
    "parameterize",
    "bounded_distortion",
    "Deformer",
    "Project",
    "mesh_from_image",
    "compatible_mesh",
    "read_mesh",
    "write_obj",
    "Error",
    "MeshError",
    "MorphError",
    "GeodesicError",
    "ParamError",
    "DeformError",
    "MeshingError",
    "InbetweenError",
    "FileError",
    "SolverWarning",
    "FrameFailure",
]


class SolverWarning(UserWarning):
    """A solver stopped short of what was asked (a stall, collapsed triangles, an unmet
    distortion bound); the result is returned, and the warning says why, in the command
    line's words."""


# ---- input checks -------------------------------------------------------------------------

def _points(V, name: str = "V") -> np.ndarray:
    a = np.asarray(V)
    if a.dtype.kind not in "fiu":
        raise MeshError(f"{name} must be an array of numbers, not of {a.dtype}")
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        raise MeshError(f"{name} must be n x 2 or n x 3, not an array of shape {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _points2(P, name: str) -> np.ndarray:
    a = np.asarray(P)
    if a.dtype.kind not in "fiu":
        raise Error(f"{name} must be an array of numbers, not of {a.dtype}")
    if a.ndim == 1 and a.shape == (2,):
        a = a.reshape(1, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise Error(f"{name} must be k x 2, not an array of shape {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _faces(F) -> np.ndarray:
    a = np.asarray(F)
    if a.dtype.kind not in "iu":
        raise MeshError(f"F must be an array of integers (vertex indices), not of {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise MeshError(f"F must be m x 3 (one row per triangle), not an array of shape {a.shape}")
    if a.dtype.kind == "u" and a.size and a.max() > np.iinfo(np.int64).max:
        raise MeshError(f"F: vertex index {a.max()} is too large")
    return np.ascontiguousarray(a, dtype=np.int64)


def _indices(S, name: str) -> np.ndarray:
    a = np.atleast_1d(np.asarray(S))
    if a.size == 0 and a.ndim == 1:
        a = a.astype(np.int64)          # [] is float64 to NumPy: an empty list of indices
    if a.dtype.kind not in "iu":
        raise Error(f"{name} must be vertex indices (integers), not {a.dtype}")
    if a.ndim != 1:
        raise Error(f"{name} must be a list of vertex indices, not an array of shape {a.shape}")
    if a.dtype.kind == "u" and a.size and a.max() > np.iinfo(np.int64).max:
        raise Error(f"{name}: vertex index {a.max()} is too large")
    return np.ascontiguousarray(a, dtype=np.int64)


def _numbers(X, name: str) -> np.ndarray:
    a = np.atleast_1d(np.asarray(X))
    if a.dtype.kind not in "fiu" or a.ndim != 1:
        raise Error(f"{name} must be a 1-D array of numbers, not {a.dtype} of shape {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _stiffness(weights) -> Optional[np.ndarray]:
    """Per-triangle stiffness weights: None, or a 1-D array of numbers (their count and
    values are checked by the library, which names the triangle)."""
    if weights is None:
        return None
    a = np.asarray(weights)
    if a.dtype.kind not in "fiu" or a.ndim != 1:
        raise DeformError("stiffness must be None or a 1-D array of numbers (one weight per "
                          f"triangle), not {a.dtype} of shape {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _keyframes(Vs, name: str = "keyframes") -> list:
    if isinstance(Vs, np.ndarray) and Vs.ndim == 3:
        Vs = list(Vs)
    Vs = list(Vs)
    if len(Vs) < 2:
        raise MorphError(f"{name}: give at least two poses, not {len(Vs)}")
    keys = [_points(V, f"keyframe {i}") for i, V in enumerate(Vs)]
    _same_counts([(f"keyframe {i}", V) for i, V in enumerate(keys)])
    return keys


def _whole(value, name: str, error: Type[Error], low: int = 1,
           high: int = 2**32 - 1) -> Optional[int]:
    """``value`` (None, or a whole number from ``low`` to ``high``) as an int; anything else is
    refused with ``error``, naming ``name``."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise error(f"{name} must be a whole number from {low} to {high}, not {value!r}")
    if not low <= int(value) <= high:
        raise error(f"{name} must be from {low} to {high}, not {int(value)}")
    return int(value)


def _real(value, name: str, error: Type[Error], *, low: float = 0.0, strict: bool = True,
          high: Optional[float] = None, high_strict: bool = False) -> Optional[float]:
    """``value`` (None, or a finite number above ``low`` (at least ``low`` unless ``strict``),
    and below ``high`` when given) as a float; anything else (NaN, infinities, other types)
    is refused with ``error``, naming ``name``."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise error(f"{name} must be a number, not {value!r}")
    x = float(value)
    want = f"> {low:g}" if strict else f">= {low:g}"
    if high is not None:
        want += f" and {'<' if high_strict else '<='} {high:g}"
    ok = math.isfinite(x) and (x > low if strict else x >= low)
    if high is not None:
        ok = ok and (x < high if high_strict else x <= high)
    if not ok:
        raise error(f"{name} must be a finite number {want}, not {x!r}")
    return x


def _number(value, name: str, error: Type[Error], **bounds) -> float:
    """As :func:`_real`, ``None`` refused too."""
    x = _real(value, name, error, **bounds)
    if x is None:
        raise error(f"{name} must be a number, not None")
    return x


def _same_counts(poses: Sequence[Tuple[str, np.ndarray]]) -> None:
    """Every pose lists as many vertices as the first (checked before the meshes are built,
    so that a short pose is blamed, not ``F``)."""
    first, a = poses[0]
    for name, b in poses[1:]:
        if len(b) != len(a):
            raise MeshError(f"{name} has {len(b)} vertices but {first} has {len(a)}: every "
                            "pose lists the same vertices, in the same order")


def _morph_options(tolerance, max_iterations) -> Tuple[Optional[float], Optional[int]]:
    return (_real(tolerance, "tolerance", MorphError),
            _whole(max_iterations, "max_iterations", MorphError))


@dataclass(frozen=True)
class FrameFailure:
    """A frame that a batch (``frames(..., on_error="nan")``) could not compute: its
    ``index`` in the batch, where it was asked (``at``: the ``t``, or the row of weights of a
    :class:`Blend`) and the ``error`` it raised (a :class:`MorphError` or
    :class:`MeshError`, which ``raise failure.error`` raises)."""

    index: int
    at: Union[float, Tuple[float, ...]]
    error: Error


def _t(t) -> float:
    """A frame's ``t`` as a float (NaN and infinities are the engine's to refuse, naming t)."""
    if isinstance(t, bool) or not isinstance(t, (int, float, np.integer, np.floating)):
        raise MorphError(f"t must be a number, not {t!r}")
    return float(t)


def _on_error(on_error) -> str:
    if on_error not in ("raise", "nan"):
        raise MorphError(f"on_error must be 'raise' or 'nan', not {on_error!r}")
    return on_error


def _placement(placement) -> str:
    if placement not in ("anchor", "fit"):
        raise MorphError(f"placement must be 'anchor' or 'fit', not {placement!r}")
    return placement


def _threads(threads) -> Optional[int]:
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)):
        raise MorphError(f"threads must be a whole number from 1 to 1024 or None, not {threads!r}")
    if not 1 <= int(threads) <= 1024:
        raise MorphError(f"threads must be from 1 to 1024, not {int(threads)}")
    return int(threads)


def _warn(info: dict) -> None:
    message = info.get("message")
    if message:
        warnings.warn(message, SolverWarning, stacklevel=3)


# ---- morphing -----------------------------------------------------------------------------

class Morph:
    """A bounded-distortion morph between two poses ``V0`` and ``V1`` of one planar mesh
    (same triangles ``F``; ``V1`` may list them in any order, corners rotated). The mesh is
    compiled once; each :meth:`frame` is a few Newton iterations, warm-started from the
    previous frame.

    Options: ``tolerance`` (Newton's gradient-norm stop, default 1e-10), ``max_iterations``
    (default 50), ``allow_inverted`` (accept a few clockwise triangles in the keyframes),
    ``warm_start`` (default True), ``threads`` (default None: one per core; a mesh from about
    6K vertices splits each frame over them; 1 is the one-thread engine; the same count gives
    the same bits, another agrees within the solver's tolerance), ``placement`` (``"anchor"``,
    the default: each frame placed by a vertex and an edge; ``"fit"``: by the rigid motion
    that best fits the keyframes, so that parts that hold still between them hold still in
    between; the command line's ``--placement``).

    >>> import numpy as np, bdmorph
    >>> V0 = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], dtype=float)
    >>> F = [[0, 1, 2], [0, 2, 3]]
    >>> V1 = V0 * [1, 2]
    >>> m = bdmorph.Morph(V0, V1, F)
    >>> bool(np.allclose(m.frame(1.0), V1 - V1.mean(0) + m.frame(1.0).mean(0)))
    True
    >>> m.frames([0, 0.5, 1]).shape
    (3, 4, 2)
    """

    def __init__(self, V0, V1, F, *, tolerance: Optional[float] = None,
                 max_iterations: Optional[int] = None, allow_inverted: bool = False,
                 warm_start: bool = True, threads: Optional[int] = None,
                 placement: str = "anchor"):
        a, b = _points(V0, "V0"), _points(V1, "V1")
        _same_counts([("V0", a), ("V1", b)])
        self._m = _native.Morph(a, b, _faces(F), *_morph_options(tolerance, max_iterations),
                                allow_inverted, warm_start, _threads(threads),
                                _placement(placement))
        self._failures: List[FrameFailure] = []

    def frame(self, t: float) -> np.ndarray:
        """The frame at ``t`` (0 is ``V0``'s shape, 1 is ``V1``'s; slightly outside [0, 1]
        extrapolates while the edge lengths stay Euclidean, as the command line's ``--t``)
        as an ``n x 2`` array."""
        return self._m.frame(_t(t))

    def frames(self, ts, *, on_error: Literal["raise", "nan"] = "raise") -> np.ndarray:
        """The frames at each of ``ts`` as a ``k x n x 2`` array (one call, the GIL released
        throughout).

        ``on_error``: ``"raise"`` (default) raises the first frame's error that cannot be
        computed (a ``t`` past where the extrapolation breaks, NaN, ...), its message led by
        which one (``ts[2]: ...``), and returns none; ``"nan"`` returns every frame, those that
        cannot be computed filled with NaN, each listed in :attr:`failures`.

        >>> import numpy as np, bdmorph
        >>> V0 = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
        >>> m = bdmorph.Morph(V0, V0 * [3, 1], [[0, 1, 2]])
        >>> m.frames([0, 1, float("nan")], on_error="nan").shape
        (3, 3, 2)
        >>> [(f.index, f.at) for f in m.failures]
        [(2, nan)]
        """
        t = _numbers(ts, "ts")
        frames, failed = self._m.frames(t, _on_error(on_error))
        self._failures = [FrameFailure(i, float(t[i]), e) for i, e in failed]
        return frames

    @property
    def failures(self) -> List[FrameFailure]:
        """The frames the last :meth:`frames` call could not compute (with
        ``on_error="nan"``; empty when every frame was computed)."""
        return list(self._failures)

    @property
    def stats(self) -> Optional[dict]:
        """The last frame's statistics: ``t``, ``newton_iterations``, ``factorizations``,
        ``cg_iterations``, ``gradient_norm``, ``flipped_triangles``,
        ``max_conformal_distortion``, ``seconds`` (None before the first frame)."""
        return self._m.stats

    @property
    def distortion(self) -> np.ndarray:
        """Each triangle's conformal distortion in the last frame, from ``V0``."""
        return self._m.distortion

    @property
    def threads(self) -> int:
        """Threads of the pool the frames are solved in."""
        return self._m.threads

    @property
    def n_vertices(self) -> int:
        """Vertices of the mesh (rows of each frame)."""
        return self._m.n_vertices

    def __repr__(self) -> str:
        return f"bdmorph.Morph({self.n_vertices} vertices)"


class Blend:
    """A bounded-distortion blend of several poses of one planar mesh by weights (one per
    pose, summing to 1).

    >>> import numpy as np, bdmorph
    >>> V0 = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
    >>> b = bdmorph.Blend([V0, V0 * 2, V0 * [1, 3]], [[0, 1, 2]])
    >>> b.frame([0.5, 0.25, 0.25]).shape
    (3, 2)
    """

    def __init__(self, keyframes: Sequence, F, *, tolerance: Optional[float] = None,
                 max_iterations: Optional[int] = None, allow_inverted: bool = False,
                 warm_start: bool = True, threads: Optional[int] = None,
                 placement: str = "anchor"):
        self._b = _native.Blend(_keyframes(keyframes), _faces(F),
                                *_morph_options(tolerance, max_iterations), allow_inverted,
                                warm_start, _threads(threads), _placement(placement))
        self._failures: List[FrameFailure] = []

    def frame(self, weights) -> np.ndarray:
        """The blend with ``weights`` as an ``n x 2`` array."""
        return self._b.frame(_numbers(weights, "weights"))

    def frames(self, weights, *, on_error: Literal["raise", "nan"] = "raise") -> np.ndarray:
        """The blends for each row of ``weights`` (``k x poses``) as a ``k x n x 2`` array.

        ``on_error``: ``"raise"`` (default) raises the first row's error (weights that do not
        sum to 1, ...), its message led by which row (``weights row 2: ...``), and returns
        none; ``"nan"`` returns every blend, those that cannot be computed filled with NaN,
        each listed in :attr:`failures`."""
        w = np.asarray(weights)
        if w.dtype.kind not in "fiu" or w.ndim != 2:
            raise MorphError(f"weights must be a k x {self.n_keyframes} array of numbers")
        w = np.ascontiguousarray(w, dtype=np.float64)
        frames, failed = self._b.frames(w, _on_error(on_error))
        self._failures = [FrameFailure(i, tuple(float(x) for x in w[i]), e) for i, e in failed]
        return frames

    @property
    def failures(self) -> List[FrameFailure]:
        """The blends the last :meth:`frames` call could not compute (with
        ``on_error="nan"``; empty when every blend was computed)."""
        return list(self._failures)

    @property
    def stats(self) -> Optional[dict]:
        """The last frame's statistics (see :attr:`Morph.stats`)."""
        return self._b.stats

    @property
    def n_keyframes(self) -> int:
        """Poses blended (the columns of ``weights``)."""
        return self._b.n_keyframes

    @property
    def threads(self) -> int:
        """Threads of the pool the frames are solved in."""
        return self._b.threads

    def __repr__(self) -> str:
        return f"bdmorph.Blend({self.n_keyframes} poses)"


class Path:
    """A morph along several poses, each reached exactly, each segment with its duration
    (relative; default equal) and easing (``"linear"``, ``"ease-in-out"`` or
    ``"cubic-bezier(x1,y1,x2,y2)"``; one for all segments or one per segment). ``t`` runs
    over [0, 1] along the whole path.

    >>> import numpy as np, bdmorph
    >>> V0 = np.array([[0, 0], [1, 0], [0, 1]], dtype=float)
    >>> p = bdmorph.Path([V0, V0 * 2, V0], [[0, 1, 2]], durations=[1, 3], easings="ease-in-out")
    >>> p.keyframe_times
    [0.0, 0.25, 1.0]
    >>> bool(np.allclose(p.frame(0.25) - p.frame(0.25).mean(0), 2 * (V0 - V0.mean(0))))
    True
    """

    def __init__(self, keyframes: Sequence, F, *, durations: Optional[Sequence[float]] = None,
                 easings: Union[None, str, Sequence[str]] = None,
                 tolerance: Optional[float] = None, max_iterations: Optional[int] = None,
                 allow_inverted: bool = False, warm_start: bool = True,
                 threads: Optional[int] = None, placement: str = "anchor"):
        keys = _keyframes(keyframes)
        if isinstance(easings, str):
            easings = [easings] * (len(keys) - 1)
        if durations is not None:
            if isinstance(durations, (str, bytes)) or not hasattr(durations, "__iter__"):
                raise MorphError(f"durations must be a list of numbers (one per segment), not "
                                 f"{durations!r}")
            durations = [_number(d, f"durations[{i}]", MorphError)
                         for i, d in enumerate(durations)]
        if easings is not None:
            easings = [str(e) for e in easings]
        self._p = _native.Path(keys, _faces(F), durations, easings,
                               *_morph_options(tolerance, max_iterations), allow_inverted,
                               warm_start, _threads(threads), _placement(placement))
        self._failures: List[FrameFailure] = []

    def frame(self, t: float) -> np.ndarray:
        """The frame at ``t`` in [0, 1] as an ``n x 2`` array."""
        return self._p.frame(_t(t))

    def frames(self, ts, *, on_error: Literal["raise", "nan"] = "raise") -> np.ndarray:
        """The frames at each of ``ts`` as a ``k x n x 2`` array.

        ``on_error``: ``"raise"`` (default) raises the first frame's error (a ``t`` outside
        [0, 1], ...), its message led by which one (``ts[2]: ...``), and returns none;
        ``"nan"`` returns every frame, those that cannot be computed filled with NaN, each
        listed in :attr:`failures`."""
        t = _numbers(ts, "ts")
        frames, failed = self._p.frames(t, _on_error(on_error))
        self._failures = [FrameFailure(i, float(t[i]), e) for i, e in failed]
        return frames

    @property
    def failures(self) -> List[FrameFailure]:
        """The frames the last :meth:`frames` call could not compute (with
        ``on_error="nan"``; empty when every frame was computed)."""
        return list(self._failures)

    @property
    def keyframe_times(self) -> list:
        """The ``t`` of each pose."""
        return self._p.keyframe_times

    @property
    def stats(self) -> Optional[dict]:
        """The last frame's statistics (see :attr:`Morph.stats`)."""
        return self._p.stats

    @property
    def threads(self) -> int:
        """Threads of the pool the frames are solved in."""
        return self._p.threads

    def __repr__(self) -> str:
        return f"bdmorph.Path({len(self.keyframe_times)} poses)"


# ---- geodesics ----------------------------------------------------------------------------

def _sources(S) -> np.ndarray:
    a = _indices(S, "sources")
    if a.size == 0:
        raise GeodesicError("sources: give at least one source vertex (the list is empty)")
    return a


class HeatGeodesics:
    """Geodesic distances on a triangle mesh (``V`` n x 3, or n x 2 for a planar one) by the
    heat method, prefactored once; each query is a few back-substitutions.

    Options: ``time_factor`` (the heat time's ``m`` in ``t = m h^2``, default 0.5),
    ``boundary`` (``"robin"`` (default), ``"neumann"``, ``"dirichlet"`` or ``"average"``),
    ``intrinsic_delaunay`` (default True), ``refine`` (intrinsic Delaunay refinement: insert
    vertices on the surface until every triangle's angles are at least this many degrees, at
    most 30; default 0, off) and ``refine_budget`` (the most vertices it inserts, as a
    fraction of the mesh's; default 0.5). Distances are always per vertex of the mesh.

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> g = bdmorph.HeatGeodesics(V, [[0, 1, 2], [0, 2, 3]])
    >>> d = g.distance([0])
    >>> float(d[0])
    0.0
    >>> g.distances_each([0, 2]).shape
    (2, 4)
    """

    def __init__(self, V, F, *, time_factor: Optional[float] = None, boundary: str = "robin",
                 intrinsic_delaunay: bool = True, refine: float = 0.0,
                 refine_budget: float = 0.5):
        self._g = _native.HeatGeodesics(_points(V), _faces(F),
                                        _real(time_factor, "time_factor", GeodesicError),
                                        boundary, intrinsic_delaunay,
                                        _real(refine, "refine", GeodesicError, strict=False),
                                        _real(refine_budget, "refine_budget", GeodesicError, strict=False))

    def distance(self, sources) -> np.ndarray:
        """Distances from the nearest of ``sources`` (a vertex or a non-empty list), an array
        of n."""
        return self._g.distance(_sources(sources))

    def distances_each(self, sources) -> np.ndarray:
        """The distances from each source alone (a vertex or a non-empty list), a ``k x n``
        array."""
        return self._g.distances_each(_sources(sources))

    @property
    def n_vertices(self) -> int:
        """Vertices of the mesh (entries of each distance field)."""
        return self._g.n_vertices

    @property
    def stats(self) -> dict:
        """What the set-up did: vertices, faces, flips, time, mean_edge, spacing,
        has_boundary, refined_vertices, refined_min_angle (degrees; 0 without refinement)."""
        return self._g.stats

    def __repr__(self) -> str:
        return f"bdmorph.HeatGeodesics({self._g.n_vertices} vertices)"


class ExactGeodesics:
    """Exact polyhedral geodesic distances and shortest paths on a triangle mesh (``V`` n x 3,
    or n x 2 for a planar one), by window propagation (Chen and Han's algorithm with Xin and
    Wang's pruning). Agrees with libigl's ``exact_geodesic`` and pygeodesic to about 1e-15 of
    the mesh's size.

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> g = bdmorph.ExactGeodesics(V, [[0, 1, 2], [0, 2, 3]])
    >>> round(float(g.distance([0])[2]), 12)
    1.414213562373
    >>> g.path(1, 3).shape
    (3, 3)
    """

    def __init__(self, V, F) -> None:
        self._g = _native.ExactGeodesics(_points(V), _faces(F))

    def distance(self, sources) -> np.ndarray:
        """Exact distances from the nearest of ``sources`` (a vertex or a non-empty list), an
        array of n."""
        return self._g.distance(_sources(sources))

    def distances_each(self, sources) -> np.ndarray:
        """The exact distances from each source alone, a ``k x n`` array."""
        return np.stack([self._g.distance(np.array([s])) for s in _sources(sources)])

    def path(self, a: int, b: int) -> np.ndarray:
        """The shortest path on the surface from vertex ``a`` to vertex ``b``: a ``k x 3``
        array of points, from ``a`` to ``b``, one wherever it crosses an edge."""
        return self._g.path(int(a), int(b))

    @property
    def n_vertices(self) -> int:
        """Vertices of the mesh."""
        return self._g.n_vertices

    @property
    def windows(self) -> int:
        """Windows the last query made (its work and memory, 56 bytes each)."""
        return self._g.windows

    def __repr__(self) -> str:
        return f"bdmorph.ExactGeodesics({self._g.n_vertices} vertices)"


def geodesic_distance(V, F, sources, *, exact: bool = False, **heat_options) -> np.ndarray:
    """Distances on the mesh from the nearest of ``sources``: by the heat method (``**heat_
    options`` as :class:`HeatGeodesics`), or exact polyhedral distances with ``exact=True``.
    For many queries on one mesh, keep a :class:`HeatGeodesics` or :class:`ExactGeodesics`.

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> float(bdmorph.geodesic_distance(V, [[0, 1, 2], [0, 2, 3]], [0], exact=True)[1])
    1.0
    """
    if exact:
        if heat_options:
            raise GeodesicError(
                f"exact=True takes no heat-method options (got {', '.join(sorted(heat_options))})")
        return ExactGeodesics(V, F).distance(sources)
    return HeatGeodesics(V, F, **heat_options).distance(sources)


# ---- parameterisation ---------------------------------------------------------------------

@overload
def parameterize(V, F, method: str = ..., *, iterations: Optional[int] = ...,
                 tolerance: Optional[float] = ..., collapse_barrier: Optional[float] = ...,
                 full_output: Literal[False] = ...) -> np.ndarray: ...
@overload
def parameterize(V, F, method: str = ..., *, iterations: Optional[int] = ...,
                 tolerance: Optional[float] = ..., collapse_barrier: Optional[float] = ...,
                 full_output: Literal[True]) -> Tuple[np.ndarray, dict]: ...
@overload
def parameterize(V, F, method: str = ..., *, iterations: Optional[int] = ...,
                 tolerance: Optional[float] = ..., collapse_barrier: Optional[float] = ...,
                 full_output: bool = ...) -> Union[np.ndarray, Tuple[np.ndarray, dict]]: ...


def parameterize(V, F, method: str = "arap", *, iterations: Optional[int] = None,
                 tolerance: Optional[float] = None, collapse_barrier: Optional[float] = None,
                 full_output: bool = False) -> Union[np.ndarray, Tuple[np.ndarray, dict]]:
    """Flattens a disk-topology mesh into the plane: an ``n x 2`` array of texture
    coordinates (with ``full_output``, also a dict: iterations, stop, energies, flipped and
    collapsed triangles, seconds, ``message``).

    ``method``: ``"tutte"``, ``"lscm"``, ``"asap"``, ``"arap"``, ``"sd"`` (symmetric
    Dirichlet), ``"mips"`` or ``"arap-newton"``. A stall or collapsed triangles are reported
    by a :class:`SolverWarning` (and ``info["message"]``).

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0, 0], [1, 0, 0.2], [1, 1, 0], [0, 1, 0.2], [0.5, 0.5, 0.5]])
    >>> F = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    >>> UV, info = bdmorph.parameterize(V, F, "lscm", full_output=True)
    >>> UV.shape, info["flipped"]
    ((5, 2), 0)
    """
    uv, info = _native.parameterize(_points(V), _faces(F), method,
                                    _whole(iterations, "iterations", ParamError),
                                    _real(tolerance, "tolerance", ParamError, strict=False),
                                    _real(collapse_barrier, "collapse_barrier", ParamError,
                                          strict=False))
    _warn(info)
    return (uv, info) if full_output else uv


@overload
def bounded_distortion(V, F, max_distortion: float, *, pins=..., init: str = ...,
                       iterations: Optional[int] = ...,
                       full_output: Literal[False] = ...) -> np.ndarray: ...
@overload
def bounded_distortion(V, F, max_distortion: float, *, pins=..., init: str = ...,
                       iterations: Optional[int] = ...,
                       full_output: Literal[True]) -> Tuple[np.ndarray, dict]: ...
@overload
def bounded_distortion(V, F, max_distortion: float, *, pins=..., init: str = ...,
                       iterations: Optional[int] = ...,
                       full_output: bool = ...) -> Union[np.ndarray, Tuple[np.ndarray, dict]]: ...


def bounded_distortion(V, F, max_distortion: float, *, pins=None, init: str = "tutte",
                       iterations: Optional[int] = None,
                       full_output: bool = False) -> Union[np.ndarray, Tuple[np.ndarray, dict]]:
    """Flattens a disk-topology mesh with every triangle's conformal distortion at most
    ``max_distortion`` (K >= 1), from a Tutte (or ``init="lscm"``) start, trying the other
    start when the first does not meet the bound. ``pins``: ``(vertices, targets)``, targets
    ``k x 2``. Returns the ``n x 2`` map (with ``full_output``, also a dict: converged,
    max_distortion, inverted, iterations, lower_bound, infeasible, worst, ``message``). An
    unmet bound is reported by a :class:`SolverWarning` saying why.

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0, 0], [1, 0, 0.2], [1, 1, 0], [0, 1, 0.2], [0.5, 0.5, 0.5]])
    >>> F = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    >>> UV, info = bdmorph.bounded_distortion(V, F, 2.0, full_output=True)
    >>> bool(info["converged"] and info["max_distortion"] <= 2.0 * 1.001)
    True
    """
    pv = pt = None
    if pins is not None:
        if isinstance(pins, (str, bytes, np.ndarray)) or not hasattr(pins, "__len__") \
                or len(pins) != 2:
            raise ParamError(f"pins must be a pair (vertices, targets), not {pins!r}")
        vertices, targets = pins
        pv, pt = _indices(vertices, "pins"), _points2(targets, "pin targets")
    k = _number(max_distortion, "max_distortion", ParamError, low=1.0, strict=False)
    uv, info = _native.bounded_distortion(_points(V), _faces(F), k, pv, pt, init,
                                          _whole(iterations, "iterations", ParamError))
    _warn(info)
    return (uv, info) if full_output else uv


# ---- posing -------------------------------------------------------------------------------

class Deformer:
    """Poses a planar mesh by handles: ``method`` ``"kvf"`` (as-Killing-as-possible fields,
    soft handles with ``weight``, default 100), ``"arap"``, ``"bounded"`` (with
    ``max_distortion``) or ``"sd"`` (symmetric Dirichlet by projected Newton, soft handles
    with ``weight``, default 100: no triangle is ever flipped or crushed; a handle stops
    short where following it would crush the mesh, and ``report["pin_residual"]`` says by
    how much). :meth:`set_pins` factors once (sd factors as it goes, reusing its factor
    while it serves); each :meth:`drag` is cheap and warm-started from the last pose.
    ``iterations`` per drag (kvf steps, default 2; arap local/global iterations, default 10;
    bounded projections, default 100; sd Newton iterations, default 4) and ``tolerance``
    (kvf, arap, sd: stop when no vertex moves more than this fraction of the mesh's size)
    trade speed for convergence; drag again to the same targets to go on converging.

    ``stiffness`` (or :meth:`set_stiffness`): one weight per triangle, each a finite number
    >= 1 (1: the mesh's own; larger holds the triangle closer to its rest shape up to a
    rotation, as After Effects' "starch"; 1000 keeps painted triangles within 1% of rigid
    under every method); None: all 1.

    >>> import numpy as np, bdmorph
    >>> V = np.array([[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1]], dtype=float)
    >>> F = [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]
    >>> d = bdmorph.Deformer(V, F, method="arap")
    >>> d.set_pins([0, 3, 5])
    >>> P = d.drag([[0, 0], [0, 1], [2.2, 1.3]])
    >>> bool(np.allclose(P[5], [2.2, 1.3])), d.report["flipped_triangles"]
    (True, 0)
    """

    def __init__(self, V, F, method: str = "kvf", *, weight: Optional[float] = None,
                 max_distortion: Optional[float] = None, iterations: Optional[int] = None,
                 tolerance: Optional[float] = None, stiffness=None):
        self._d = _native.Deformer(
            _points(V), _faces(F), method, _real(weight, "weight", DeformError),
            _real(max_distortion, "max_distortion", DeformError, low=1.0, strict=False),
            _whole(iterations, "iterations", DeformError),
            _real(tolerance, "tolerance", DeformError, strict=False),
            _stiffness(stiffness))

    def set_pins(self, pins) -> None:
        """Sets the handles (vertex indices; at least one)."""
        a = _indices(pins, "pins")
        if a.size == 0:
            raise DeformError("pins: give at least one handle vertex (the list is empty)")
        self._d.set_pins(a)

    def drag(self, targets) -> np.ndarray:
        """Moves the handles to ``targets`` (``k x 2``, in the pins' order); the pose,
        ``n x 2``."""
        return self._d.drag(_points2(targets, "targets"))

    def set_weight(self, weight: float) -> None:
        """The handles' weight of kvf (refactors) or sd; the pins stay."""
        self._d.set_weight(_number(weight, "weight", DeformError))

    def set_stiffness(self, weights) -> None:
        """Each triangle's stiffness: a 1-D array, one weight per triangle, each finite and
        >= 1 (None: all 1). Refactors when pins are set; the pins and the pose stay."""
        self._d.set_stiffness(_stiffness(weights))

    @property
    def stiffness(self) -> Optional[np.ndarray]:
        """The stiffness set, one weight per triangle, or None (all 1)."""
        return self._d.stiffness

    def reset(self) -> None:
        """Back to the rest shape."""
        self._d.reset()

    def set_positions(self, positions) -> None:
        """Replaces the pose (``n x 2``), e.g. to undo."""
        self._d.set_positions(_points(positions, "positions"))

    @property
    def positions(self) -> np.ndarray:
        """The pose, ``n x 2``."""
        return self._d.positions

    @property
    def pins(self) -> List[int]:
        """The handles (vertex indices), in :meth:`set_pins`' order."""
        return self._d.pins

    @property
    def method(self) -> str:
        """``"kvf"``, ``"arap"``, ``"bounded"`` or ``"sd"``."""
        return self._d.method

    @property
    def report(self) -> Optional[dict]:
        """What the last drag did: iterations, energy, last_change, flipped_triangles,
        pin_residual, max_distortion, bound_met."""
        return self._d.report

    def __repr__(self) -> str:
        return f"bdmorph.Deformer({self.method}, {len(self.pins)} pins)"


# ---- files and pictures -------------------------------------------------------------------

# ---- projects -----------------------------------------------------------------------------

class Project:
    """A project the studio saved (or ``bdmorph mesh CHARACTER.psd -o project.json`` wrote),
    animated as the studio plays and exports it: each keyframe's pose, the easing between
    them, and for a character in parts (from a layered picture) each part's BDMORPH frame
    placed so that the joints meet.

    :meth:`frame` gives each part's positions by its name (``"mesh"`` for a project without
    parts); :meth:`positions` every vertex's. :attr:`parts`, :attr:`joints` and
    :attr:`draw_order` describe the character.

    >>> import bdmorph                                   # doctest: +SKIP
    >>> p = bdmorph.Project("figure.json")               # doctest: +SKIP
    >>> p.draw_order                                     # doctest: +SKIP
    ['torso', 'head', 'upper_arm_l', 'forearm_l', 'upper_arm_r', 'forearm_r']
    >>> p.frame(0.5)["forearm_l"].shape                  # doctest: +SKIP
    (182, 2)
    """

    def __init__(self, path) -> None:
        self._p = _native.Project(str(path))

    def rest(self) -> Tuple[np.ndarray, np.ndarray]:
        """The rest mesh ``(V, F)``: V ``n x 2``, F ``m x 3`` (parts' triangles in draw order)."""
        return self._p.rest()

    @property
    def times(self) -> List[float]:
        """The keyframes' times in seconds (the first is 0)."""
        return self._p.times

    @property
    def duration(self) -> float:
        """The last keyframe's time in seconds."""
        return self._p.duration

    @property
    def parts(self) -> List[dict]:
        """The parts, bottom first: ``{"name", "vertices": (first, end), "faces": (first,
        end)}``; empty for a project of one mesh."""
        return self._p.parts

    @property
    def joints(self) -> np.ndarray:
        """The joints: a ``k x 2`` int64 array of vertex pairs that move together."""
        return self._p.joints

    @property
    def draw_order(self) -> List[str]:
        """The parts' names bottom first: each is drawn over the ones before it."""
        return self._p.draw_order

    def positions(self, time: float) -> np.ndarray:
        """Every vertex at ``time`` seconds (clamped to the animation): ``n x 2``."""
        return self._p.positions(_number(time, "time", MorphError, low=-math.inf))

    def frame(self, time: float) -> Dict[str, np.ndarray]:
        """Each part's positions at ``time`` seconds, by name (``{"mesh": ...}`` without
        parts)."""
        return self._p.frame(_number(time, "time", MorphError, low=-math.inf))


def mesh_from_image(path, vertices: int = 2000, *, tolerance: Optional[float] = None,
                    min_angle: Optional[float] = None,
                    threshold: Optional[float] = None) -> Tuple[np.ndarray, np.ndarray]:
    """Meshes a picture's subject (its opaque part; for an opaque picture, what differs from
    the background): ``(V, F)`` with about ``vertices`` vertices, ``V`` ``n x 2`` in the
    picture's pixels (y up), ready to morph or pose.

    Options: ``vertices`` (3 to 20,000,000), ``tolerance`` (how far, in pixels, the outline
    may be simplified; > 0, default 1), ``min_angle`` (the smallest triangle angle, in
    degrees, from 0 to 33; default 28), ``threshold`` (in [0, 1): the opacity, colour
    difference or brightness the subject is traced at)."""
    n = _whole(vertices, "vertices", MeshingError, low=3, high=20_000_000)
    if n is None:
        raise MeshingError("vertices must be a whole number from 3 to 20000000, not None")
    return _native.mesh_from_image(
        str(path), n, _real(tolerance, "tolerance", MeshingError),
        _real(min_angle, "min_angle", MeshingError, strict=False, high=33.0),
        _real(threshold, "threshold", MeshingError, strict=False, high=1.0, high_strict=True))


def compatible_mesh(a, b, matches=None, vertices: int = 2000
                    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """The compatible mesh of two drawings of one subject (pictures with transparency, the
    same pieces and holes): ``(VA, F, VB, report)``. ``VA`` is drawing A's mesh in its
    pixels (y up), ``VB`` the same triangles laid over drawing B, none flipped; ``F`` is
    ``m x 3``. ``matches`` (``k x 4``: AX, AY, BX, BY, in pixels from each picture's top-left
    corner) pairs points of A with the points of B they become. ``report`` has
    ``max_distortion``, ``outline_error``, ``pairs`` (each ``met``, ``error``, ``reason``)...

    The in-betweens as arrays: ``Morph(VA, VB, F).frames(ts)``.

    >>> VA, F, VB, report = bdmorph.compatible_mesh("a.png", "b.png")  # doctest: +SKIP
    >>> frames = bdmorph.Morph(VA, VB, F).frames(np.linspace(0, 1, 24))  # doctest: +SKIP
    """
    n = _whole(vertices, "vertices", InbetweenError, low=3, high=20_000_000)
    if n is None:
        raise InbetweenError("vertices must be a whole number from 3 to 20000000, not None")
    pairs = None
    if matches is not None:
        try:
            pairs = np.ascontiguousarray(np.asarray(matches, dtype=np.float64).reshape(-1, 4))
        except (TypeError, ValueError) as e:
            raise InbetweenError(f"matches must be k x 4 numbers (AX, AY, BX, BY): {e}") from None
    return _native.compatible_mesh(str(a), str(b), pairs, n)


def read_mesh(path) -> Tuple[np.ndarray, np.ndarray]:
    """Reads an OBJ or OFF triangle mesh: ``(V, F)``, ``V`` ``n x 3`` float64, ``F``
    ``m x 3`` int64."""
    return _native.read_mesh(str(path))


def write_obj(path, V, F) -> None:
    """Writes ``V`` (``n x 2`` or ``n x 3``) and ``F`` as OBJ, atomically (a reader sees the
    old file or the new one, never half of one); coordinates read back bit for bit."""
    _native.write_obj(str(path), _points(V), _faces(F))
