"""Exceptions and warnings raised by meshladar.

Every exception subclasses the matching builtin as well as :class:`MeshladarError`, so a
user can catch either ``ValueError`` or ``meshladar.errors.MeshladarError``.
"""

from __future__ import annotations

import importlib
import os
import sys

__all__ = [
    "MeshladarError",
    "ParameterError",
    "MaterialFileError",
    "GeometryError",
    "PhantomSpecError",
    "ModelError",
    "MeshladarWarning",
    "LobeSamplingWarning",
    "EnergyConservationWarning",
    "user_stacklevel",
]

_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep
_IMPORTLIB = os.path.dirname(os.path.abspath(importlib.__file__)) + os.sep


def user_stacklevel() -> int:
    """The ``stacklevel``, for a warning raised by this function's caller, of the first
    frame outside meshladar and the import machinery: the user's own call (or import line),
    however many of meshladar's layers lie between. ``warnings`` itself skips the frozen
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


class MeshladarError(Exception):
    """Base class of every error meshladar raises on purpose."""


class ParameterError(MeshladarError, ValueError):
    """A parameter is out of its valid range, non-finite or of the wrong kind."""


class MaterialFileError(MeshladarError, ValueError):
    """A material table (TOML) is unreadable or one of its entries is invalid."""


class GeometryError(MeshladarError, ValueError):
    """A scene's geometry is invalid: overlapping shapes, a mesh that fails its checks."""


class PhantomSpecError(MeshladarError, ValueError):
    """A phantom spec (TOML) is unreadable or one of its fields is invalid."""


class ModelError(MeshladarError, NotImplementedError):
    """A BRDF lacks a method the run needs (``projected``; ``bistatic`` for a bistatic
    receiver)."""


class MeshladarWarning(UserWarning):
    """Base class of meshladar's warnings: a soft precondition is not met."""


class LobeSamplingWarning(MeshladarWarning):
    """The rays are too sparse for a coating's specular lobe on a curved part: its glint is
    undersampled (the warning names the ray spacing that resolves it)."""


class EnergyConservationWarning(MeshladarWarning):
    """A coating reflects more light than it receives at some incidence angle."""
