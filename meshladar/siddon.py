"""Deprecated alias of meshladar.forward.siddon (one release).

The old module name is the new module itself (sys.modules), so every name it held,
private ones included, stays reachable at the old path."""

from ._deprecated import warn_moved
import sys

from .forward import siddon as _module

warn_moved("siddon", "forward.siddon")

sys.modules[__name__] = _module
