"""Deprecated alias of meshladar.hits (one release)."""

from .._deprecated import warn_moved
from ..hits import *  # noqa: F401,F403
from ..hits import Hits, ViewHits  # noqa: F401

warn_moved("raytrace.hits", "hits")
