"""Deprecated alias of meshladar.fit.shapes (one release)."""

from .fit.shapes import SHAPE_KINDS, SceneFit, find_shapes, fit_scene

__all__ = ["find_shapes", "fit_scene", "SceneFit", "SHAPE_KINDS"]
