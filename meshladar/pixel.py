"""Deprecated alias of meshladar.forward.pixel (one release).

The old module name is the new module itself (sys.modules), so every name it held,
private ones included, stays reachable at the old path."""

from ._deprecated import warn_moved
import sys

from .forward import pixel as _module

warn_moved("pixel", "forward.pixel")

sys.modules[__name__] = _module
