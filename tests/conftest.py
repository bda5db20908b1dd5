"""Shared test scenes, built once from the phantom library (the one source of the paper's
phantoms and coatings), imported by the test modules that use them; the command-line
tests' working folder (``files``)."""

from __future__ import annotations

import struct

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.io import save_sinogram
from meshladar.materials import ALUMINUM, DARK_GRAY

#: The paper's disk pair, dark gray large disk and aluminium small disk (Figs 9-11).
PAIR = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)


def pytest_collection_modifyitems(config, items):
    """Checks marked ``exhaustive`` (hours of CPU) run only when the marker expression
    names them (``pytest -m exhaustive``): not in the default run, nor under ``-m slow``
    or ``-m "not slow"``."""
    if "exhaustive" in (config.getoption("markexpr") or ""):
        return
    kept = [item for item in items if item.get_closest_marker("exhaustive") is None]
    if len(kept) < len(items):
        config.hook.pytest_deselected(items=[i for i in items if i not in kept])
        items[:] = kept


@pytest.fixture
def files(tmp_path, monkeypatch):
    """The working folder: a unit box (box.stl), an all-degenerate STL (flat.stl), a file
    (f.txt) and a small sinogram (s.npz)."""
    monkeypatch.chdir(tmp_path)
    trimesh.creation.box().export(tmp_path / "box.stl")
    flat = np.array([[0, 0, 1], [0, 0, 0], [1, 0, 0], [2, 0, 0]], np.float32)   # collinear
    (tmp_path / "flat.stl").write_bytes(bytes(80) + struct.pack("<I", 1) + flat.tobytes()
                                        + bytes(2))
    (tmp_path / "f.txt").write_text("a file")
    save_sinogram(tmp_path / "s.npz", ml.Sinogram(np.ones((8, 16)),
                                                  angles_deg=np.arange(8) * 45.0,
                                                  bin_edges=np.linspace(-1.0, 1.0, 17)))
    return tmp_path
