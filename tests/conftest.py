"""Shared test scenes, built once from the phantom library (the one source of the paper's
phantoms and coatings), imported by the test modules that use them."""

from __future__ import annotations

import meshladar as ml
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
