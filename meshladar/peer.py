"""Deprecated alias of meshladar.studies.peer (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.peer.x
and meshladar.studies.peer.x are one name, also when a test patches one of them.
"""

import sys

from .studies import peer as _module

sys.modules[__name__] = _module
