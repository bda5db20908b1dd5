"""meshladar's version, in the foundation layer: modules that record it in their files
(:mod:`meshladar.io`, :mod:`meshladar.runs`) import it from here at their top, which works
while ``meshladar/__init__.py`` is still being imported (``from . import __version__`` would
not, once the engine imports them at its top)."""

from __future__ import annotations

__all__ = ["__version__"]

__version__ = "0.1.0"
