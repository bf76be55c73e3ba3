"""Projects: a character in parts from a layered picture (an OpenRaster file written here),
meshed by the command line, given a second keyframe, and animated from Python as the studio
plays it: parts, joints and draw order as in the file, joints together along the animation,
keyframes reproduced exactly."""

import json
import math
import zipfile

import numpy as np
import pytest

import bdmorph
from conftest import write_png


def rectangle_layer(w, h, box, colour):
    rgba = np.zeros((h, w, 4), dtype=np.uint8)
    x0, y0, x1, y1 = box
    rgba[y0:y1, x0:x1] = [*colour, 255]
    return rgba


def write_ora(path, tmp, layers, size):
    """An OpenRaster file of canvas-sized layers (bottom first)."""
    w, h = size
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(zipfile.ZipInfo("mimetype"), "image/openraster")
        entries = []
        for i, (name, rgba) in enumerate(layers):
            png = tmp / f"layer{i}.png"
            write_png(png, rgba)
            z.write(png, f"data/layer{i}.png")
            entries.append(f'<layer name="{name}" src="data/layer{i}.png" x="0" y="0"/>')
        stack = "".join(reversed(entries))
        z.writestr("stack.xml", f'<image w="{w}" h="{h}"><stack>{stack}</stack></image>')


@pytest.fixture
def arm(tmp_path, cli):
    """A body and a two-segment arm, meshed into a project with the arm turned at keyframe 2."""
    size = (160, 100)
    layers = [
        ("body", rectangle_layer(*size, (10, 20, 50, 90), (40, 60, 220))),
        ("upper", rectangle_layer(*size, (40, 30, 100, 45), (40, 180, 60))),
        ("lower", rectangle_layer(*size, (90, 31, 150, 44), (220, 40, 40))),
    ]
    write_ora(tmp_path / "arm.ora", tmp_path, layers, size)
    cli("mesh", tmp_path / "arm.ora", "-o", tmp_path / "arm.json", "--vertices", "600")
    doc = json.loads((tmp_path / "arm.json").read_text())
    parts = {p["name"]: p for p in doc["parts"]}
    V = np.array(doc["mesh"]["positions"])
    # Keyframe 2: the arm (both segments) turned 60 degrees about the shoulder joint.
    shoulder = next(
        a for a, b in doc["joints"]
        if {part_of(parts, a), part_of(parts, b)} == {"body", "upper"}
    )
    c, s = math.cos(math.radians(60)), math.sin(math.radians(60))
    P = V.copy()
    for name in ("upper", "lower"):
        a, b = parts[name]["vertices"]
        d = V[a:b] - V[shoulder]
        P[a:b] = V[shoulder] + d @ np.array([[c, s], [-s, c]])
    doc["keyframes"].append({"time": 2.0, "easing": "linear", "positions": P.tolist(), "pins": []})
    (tmp_path / "arm.json").write_text(json.dumps(doc))
    return tmp_path / "arm.json", V, P


def part_of(parts, v):
    return next(n for n, p in parts.items() if p["vertices"][0] <= v < p["vertices"][1])


def test_a_character_animates_with_its_joints_together(arm):
    path, V, P = arm
    p = bdmorph.Project(path)
    assert p.draw_order == ["body", "upper", "lower"]
    assert [q["name"] for q in p.parts] == ["body", "upper", "lower"]
    assert p.joints.shape == (2, 2) and p.joints.dtype == np.int64
    assert p.times == [0.0, 2.0] and p.duration == 2.0
    size = np.ptp(V, axis=0).max()
    # The keyframes are reproduced exactly (to round-off), and the joints hold between them.
    assert np.abs(p.positions(0.0) - V).max() <= 1e-9 * size
    assert np.abs(p.positions(2.0) - P).max() <= 1e-9 * size
    for t in np.linspace(0.0, 2.0, 21):
        X = p.positions(t)
        gaps = np.linalg.norm(X[p.joints[:, 0]] - X[p.joints[:, 1]], axis=1)
        assert gaps.max() <= 1e-9 * size, t
    # frame() splits the same positions by part.
    f = p.frame(1.0)
    X = p.positions(1.0)
    for q in p.parts:
        a, b = q["vertices"]
        assert np.array_equal(f[q["name"]], X[a:b])
    Vr, F = p.rest()
    assert Vr.shape == V.shape and F.shape[1] == 3


def test_a_project_of_one_keyframe_and_a_missing_file_say_why(tmp_path, arm):
    path, _, _ = arm
    doc = json.loads(path.read_text())
    doc["keyframes"] = doc["keyframes"][:1]
    one = tmp_path / "one.json"
    one.write_text(json.dumps(doc))
    with pytest.raises(bdmorph.MorphError, match="one keyframe"):
        bdmorph.Project(one).frame(0.0)
    with pytest.raises(bdmorph.FileError):
        bdmorph.Project(tmp_path / "missing.json")
    with pytest.raises(bdmorph.MorphError):
        bdmorph.Project(path).positions(float("nan"))
