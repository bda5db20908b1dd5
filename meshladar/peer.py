"""Deprecated alias of meshladar.studies.peer (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.peer.x
and meshladar.studies.peer.x are one name, also when a test patches one of them.
"""

from ._deprecated import warn_moved
import sys

from .studies import peer as _module

warn_moved("peer", "studies.peer")

sys.modules[__name__] = _module
