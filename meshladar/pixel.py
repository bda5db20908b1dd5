"""Deprecated alias of meshladar.forward.pixel (one release).

The old module name is the new module itself (sys.modules), so every name it held,
private ones included, stays reachable at the old path."""

import sys

from .forward import pixel as _module

sys.modules[__name__] = _module
