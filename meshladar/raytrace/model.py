"""Deprecated alias of meshladar.forward.mesh (one release).

The entry points moved up to the forward stage (layer 7); this alias loads them by name
so that the ray-casting stage imports nothing above it."""

import importlib
import sys

sys.modules[__name__] = importlib.import_module("meshladar.forward.mesh")
