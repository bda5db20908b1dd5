"""Deprecated names, for one release: a module that moved warns once, when it is imported,
naming its new home (foundation layer; it imports nothing of meshladar)."""

from __future__ import annotations

import importlib
import os
import sys
import warnings

__all__ = ["warn_moved"]

_PACKAGE = os.path.dirname(os.path.abspath(__file__))
_IMPORTLIB = os.path.dirname(os.path.abspath(importlib.__file__))


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside meshladar and the import machinery, so
    the warning points at the user's import line. ``warnings`` itself skips the frozen
    importlib frames when it counts, so they are not counted here either."""
    frame, level = sys._getframe(2), 2
    while frame is not None:
        name = frame.f_code.co_filename
        internal = "importlib" in name and "_bootstrap" in name     # as warnings judges it
        if not internal and not os.path.abspath(name).startswith((_PACKAGE, _IMPORTLIB)):
            return level
        frame = frame.f_back
        level += 0 if internal else 1
    return 2


def warn_moved(old: str, new: str) -> None:
    """Warn that ``meshladar.<old>`` is deprecated in favour of ``meshladar.<new>``."""
    warnings.warn(f"meshladar.{old} is deprecated and will be removed in the next release: "
                  f"use meshladar.{new}", DeprecationWarning, stacklevel=_caller_level())
