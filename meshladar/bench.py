"""Deprecated alias of meshladar.studies.bench (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.bench.x
and meshladar.studies.bench.x are one name, also when a test patches one of them.
"""

from ._deprecated import warn_moved
import sys

from .studies import bench as _module

warn_moved("bench", "studies.bench")

sys.modules[__name__] = _module
