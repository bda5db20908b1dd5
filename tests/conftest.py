"""Shared test scenes, built once from the phantom library (the one source of the paper's
phantoms and coatings), imported by the test modules that use them."""

from __future__ import annotations

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

#: The paper's disk pair, dark gray large disk and aluminium small disk (Figs 9-11).
PAIR = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)

