"""Deprecated alias of meshladar.studies.paper (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.paper.x
and meshladar.studies.paper.x are one name, also when a test patches one of them.
"""

from ._deprecated import warn_moved
import sys

from .studies import paper as _module

warn_moved("paper", "studies.paper")

sys.modules[__name__] = _module
