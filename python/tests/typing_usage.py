"""The package as a user calls it, for a type checker: CI runs mypy over this file with the
package installed (`mypy --strict`, .ci/run; pyright passes too), and test_typing.py runs it, so
that it is both well typed and true. Not collected by pytest (its name is not test_*)."""

from __future__ import annotations

import pathlib
from typing import Dict, List, Tuple

import numpy as np
import numpy.typing as npt

import bdmorph


def square() -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """A 3 x 3 grid of the unit square, eight counter-clockwise triangles."""
    xs, ys = np.meshgrid(np.linspace(0.0, 1.0, 3), np.linspace(0.0, 1.0, 3))
    V = np.column_stack([xs.ravel(), ys.ravel()])
    F: List[List[int]] = []
    for j in range(2):
        for i in range(2):
            a = j * 3 + i
            F += [[a, a + 1, a + 4], [a, a + 4, a + 3]]
    return V, np.array(F, dtype=np.int64)


def main(picture: pathlib.Path, folder: pathlib.Path) -> List[str]:
    """Runs every entry point once; returns what it saw, one line each."""
    seen: List[str] = []
    V0, F = square()
    V1 = V0 @ np.array([[0.9, 0.3], [-0.3, 0.9]])

    m = bdmorph.Morph(V0, V1, F, tolerance=1e-10, max_iterations=50, threads=1)
    half: np.ndarray = m.frame(0.5)
    seen.append(f"frame {half.shape}")
    frames = m.frames(np.linspace(0.0, 1.0, 5))
    seen.append(f"frames {frames.shape}, flipped {m.stats['flipped_triangles'] if m.stats else -1}")
    tried = m.frames([0.0, 1.0, float("nan")], on_error="nan")
    for failure in m.failures:
        seen.append(f"failed ts[{failure.index}] = {failure.at}: {type(failure.error).__name__}")
    seen.append(f"nan frames {int(np.isnan(tried[:, 0, 0]).sum())}")
    try:
        m.frames([0.0, float("inf")])
    except bdmorph.MorphError as e:
        seen.append(f"raised {str(e).split(':')[0]}")

    b = bdmorph.Blend([V0, V1, V0 * 1.5], F)
    blended = b.frame([0.5, 0.25, 0.25])
    rows = b.frames(np.array([[1.0, 0.0, 0.0], [0.0, 0.5, 0.5]]))
    seen.append(f"blend {blended.shape} {rows.shape} of {b.n_keyframes}")

    p = bdmorph.Path([V0, V1, V0], F, durations=[1.0, 2.0], easings="ease-in-out")
    times: List[float] = p.keyframe_times
    seen.append(f"path {p.frames([0.0, 0.5, 1.0]).shape} at {times}")

    V3 = np.column_stack([V0, 0.2 * V0[:, 0] * V0[:, 1]])
    g = bdmorph.HeatGeodesics(V3, F, time_factor=0.5, boundary="robin")
    d = g.distance([0])
    each = g.distances_each([0, 8])
    seen.append(f"geodesic {d.shape} {each.shape} max {float(d.max()):.2f}")
    exact = bdmorph.ExactGeodesics(V3, F)
    path = exact.path(0, 8)
    nearest = bdmorph.geodesic_distance(V3, F, [0, 8], exact=True)
    seen.append(f"exact {exact.distance(0).shape} path {path.shape} {nearest.shape} {exact.windows}")

    uv = bdmorph.parameterize(V3, F, "lscm")
    seen.append(f"uv {uv.shape}")
    uv, info = bdmorph.parameterize(V3, F, "arap", iterations=20, full_output=True)
    seen.append(f"uv {uv.shape} after {info['iterations']} iterations")
    flat = bdmorph.bounded_distortion(V3, F, 2.0)
    seen.append(f"bounded {flat.shape}")
    flat, report = bdmorph.bounded_distortion(V3, F, 2.0, pins=([0], [[0.0, 0.0]]),
                                              full_output=True)
    seen.append(f"bounded converged {bool(report['converged'])}")

    dfm = bdmorph.Deformer(V0, F, "kvf", weight=100.0, iterations=4)
    dfm.set_pins([0, 8])
    pose = dfm.drag([[0.0, 0.0], [1.2, 1.1]])
    seen.append(f"pose {pose.shape}, pins {dfm.pins}, {dfm.method}")

    PV, PF = bdmorph.mesh_from_image(picture, vertices=200)
    seen.append(f"picture mesh {PV.shape[1]} {PF.shape[1]}")
    target = folder / "square.obj"
    bdmorph.write_obj(target, V0, F)
    RV, RF = bdmorph.read_mesh(target)
    seen.append(f"read back {RV.shape} {RF.shape}")

    try:
        project = bdmorph.Project(folder / "character.json")
        order: List[str] = project.draw_order
        parts: Dict[str, npt.NDArray[np.float64]] = project.frame(0.5)
        seen.append(f"project {order} {len(parts)} {project.joints.shape} {project.duration}")
    except bdmorph.FileError as e:
        seen.append(f"no project: {e}")

    try:
        bdmorph.Deformer(V0, F, weight=-1.0)
    except bdmorph.Error as e:
        seen.append(f"refused: {e}")
    return seen
