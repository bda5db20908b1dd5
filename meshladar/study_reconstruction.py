"""Deprecated alias of meshladar.studies.reconstruction (one release).

The alias is the module itself (its entry in sys.modules), so that meshladar.study_reconstruction.x
and meshladar.studies.reconstruction.x are one name, also when a test patches one of them.
"""

import sys

from .studies import reconstruction as _module

sys.modules[__name__] = _module
