"""Deprecated alias of meshladar.io (one release).

Result files (atomic writes, no pickle) are saved and loaded by :mod:`meshladar.io`.
"""

from __future__ import annotations

from ._deprecated import warn_moved
from .io import *  # noqa: F401,F403
from .io import (ResultFileError, describe_scene, load_result, load_sinogram, load_waveforms,
                 save_result, save_sinogram, save_waveforms, write_atomic, write_text_atomic)
from .io import _SWEPT, _atomic, _jsonable  # noqa: F401  (private names importers used)

warn_moved("results", "io")

__all__ = ["save_result", "load_result", "write_atomic", "write_text_atomic", "save_sinogram",
           "load_sinogram", "save_waveforms", "load_waveforms", "describe_scene",
           "ResultFileError"]
