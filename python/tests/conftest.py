"""Shared helpers: the command-line program to compare against, meshes made in code, and the
shared data folder (tests that need it say so when it is absent)."""

import os
import pathlib
import subprocess
import struct
import zlib

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared" / "data"


def cli_path() -> pathlib.Path:
    """The `bdmorph` program: $BDMORPH_BIN, or the repository's release build."""
    path = pathlib.Path(os.environ.get("BDMORPH_BIN", REPO / "target" / "release" / "bdmorph"))
    if not path.is_file():
        pytest.fail(
            f"the command line program is needed to compare against and is not at {path}: "
            "run `cargo build --release` first (or set BDMORPH_BIN)"
        )
    return path


@pytest.fixture
def cli():
    """Runs `bdmorph ARGS...`; returns the completed process (check=False)."""
    path = cli_path()

    def run(*args, check=True):
        done = subprocess.run([str(path), *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"bdmorph {' '.join(map(str, args))} failed: {done.stderr}")
        return done

    return run


def shared(relative: str) -> pathlib.Path:
    path = SHARED / relative
    if not SHARED.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"the shared data folder {SHARED} is missing, but CI must have it")
        pytest.skip(f"the shared data folder {SHARED} is absent (../shared/data beside the repository)")
    assert path.is_file(), f"{path} is missing from the shared data"
    return path


def grid(nx: int, ny: int, size=(1.0, 1.0)):
    """A rectangle of (nx+1) x (ny+1) vertices, two counter-clockwise triangles per cell,
    diagonals alternating."""
    xs, ys = np.meshgrid(np.linspace(0, size[0], nx + 1), np.linspace(0, size[1], ny + 1))
    V = np.column_stack([xs.ravel(), ys.ravel()])
    F = []
    for j in range(ny):
        for i in range(nx):
            a = j * (nx + 1) + i
            b, c, d = a + 1, a + nx + 2, a + nx + 1
            if (i + j) % 2 == 0:
                F += [[a, b, c], [a, c, d]]
            else:
                F += [[a, b, d], [b, c, d]]
    return V, np.array(F, dtype=np.int64)


def bend(V, angle: float):
    """The strip bent into an arc of `angle` radians about its left edge's bottom (no flips
    for moderate angles)."""
    width = V[:, 0].max() - V[:, 0].min()
    if angle == 0:
        return V.copy()
    r = width / angle
    theta = V[:, 0] / width * angle
    rad = r - V[:, 1]
    return np.column_stack([rad * np.sin(theta), r - rad * np.cos(theta)])


def bump(V2, height=0.3):
    """A disk-topology surface: the planar grid lifted into a smooth bump."""
    c = V2.mean(0)
    r2 = ((V2 - c) ** 2).sum(1)
    z = height * np.exp(-r2 / (0.25 * r2.max()))
    return np.column_stack([V2, z])


def write_png(path, rgba: np.ndarray):
    """An RGBA PNG from an h x w x 4 uint8 array (no imaging library needed)."""
    h, w, _ = rgba.shape
    raw = b"".join(b"\x00" + rgba[y].tobytes() for y in range(h))

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    pathlib.Path(path).write_bytes(png)


def disk_picture(size=160):
    """A picture of an opaque disk with a square hole, on transparency."""
    y, x = np.mgrid[0:size, 0:size] + 0.5
    d = np.hypot(x - size / 2, y - size / 2)
    inside = (d < 0.4 * size) & (np.maximum(abs(x - size / 2), abs(y - size / 2)) > 0.1 * size)
    rgba = np.zeros((size, size, 4), dtype=np.uint8)
    rgba[..., 0] = 200
    rgba[..., 2] = 80
    rgba[..., 3] = np.where(inside, 255, 0)
    return rgba


def read_vt(path):
    """The `vt` lines of an OBJ file as an array."""
    rows = [list(map(float, line.split()[1:3])) for line in open(path) if line.startswith("vt ")]
    return np.array(rows)


def read_numbers(path):
    """One number per line (a distance field written by `bdmorph geodesic`)."""
    return np.array([float(line) for line in open(path) if line.strip()])
