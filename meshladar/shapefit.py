"""Deprecated alias of meshladar.fit.shapes (one release)."""

from ._deprecated import warn_moved
from .fit.shapes import SHAPE_KINDS, SceneFit, find_shapes, fit_scene

warn_moved("shapefit", "fit.shapes")

__all__ = ["find_shapes", "fit_scene", "SceneFit", "SHAPE_KINDS"]
