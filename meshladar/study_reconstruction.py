"""Deprecated alias of meshladar.studies.reconstruction (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.study_reconstruction.x
and meshladar.studies.reconstruction.x are one name, also when a test patches one of them.
"""

from ._deprecated import warn_moved
import sys

from .studies import reconstruction as _module

warn_moved("study_reconstruction", "studies.reconstruction")

sys.modules[__name__] = _module
