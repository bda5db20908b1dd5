"""Deprecated alias of meshladar.forward.mesh (one release).

The entry points moved up to the forward stage (layer 7); this alias loads them by name
so that the ray-casting stage imports nothing above it."""

from .._deprecated import warn_moved
import importlib
import sys

warn_moved("raytrace.model", "forward.mesh")

sys.modules[__name__] = importlib.import_module("meshladar.forward.mesh")
