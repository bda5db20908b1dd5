"""Deprecated names, for one release: a module that moved warns once, when it is imported,
naming its new home (foundation layer; it imports only :mod:`.errors`)."""

from __future__ import annotations

import warnings

from .errors import user_stacklevel

__all__ = ["warn_moved"]


def warn_moved(old: str, new: str) -> None:
    """Warn that ``meshladar.<old>`` is deprecated in favour of ``meshladar.<new>``."""
    warnings.warn(f"meshladar.{old} is deprecated and will be removed in the next release: "
                  f"use meshladar.{new}", DeprecationWarning, stacklevel=user_stacklevel())
