"""Deprecated alias of meshladar.hits (one release)."""

from ..hits import *  # noqa: F401,F403
from ..hits import Hits, ViewHits  # noqa: F401
