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
    "BounceWarning",
    "EnergyConservationWarning",
    "RecordLengthWarning",
    "EmptyScanWarning",
    "user_stacklevel",
]

_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep
_IMPORTLIB = os.path.dirname(os.path.abspath(importlib.__file__)) + os.sep


def user_stacklevel() -> int:
    """The ``stacklevel``, for a warning raised by this function's caller, of the first
    frame outside meshladar and the import machinery: the user's own call (or import line),
    however many of meshladar's layers lie between. ``warnings`` itself skips the frozen
    importlib frames when it counts, so they are not counted here either.

    Returns
    -------
    int
        The ``stacklevel`` (2 or more) for :func:`warnings.warn` called by this function's
        caller: that of the first frame, walking outwards from the caller's caller, whose
        file lies outside the meshladar package folder and the ``importlib`` folder and
        whose code does not run in a meshladar module's namespace (a dataclass's generated
        ``__init__``); frozen importlib bootstrap frames are skipped and not counted; 2 if
        no such frame exists.
    """
    frame, level = sys._getframe(2), 2
    while frame is not None:
        name = frame.f_code.co_filename
        internal = "importlib" in name and "_bootstrap" in name     # as warnings judges it
        # code made at run time in one of meshladar's modules (a dataclass's __init__,
        # file "<string>") is meshladar's too
        ours = str(frame.f_globals.get("__name__", "")).partition(".")[0] == "meshladar"
        if not internal and not ours \
                and not os.path.abspath(name).startswith((_PACKAGE, _IMPORTLIB)):
            return level
        frame = frame.f_back
        level += 0 if internal else 1
    return 2


class MeshladarError(Exception):
    """Base class of every error meshladar raises on purpose.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class ParameterError(MeshladarError, ValueError):
    """A parameter is out of its valid range, non-finite or of the wrong kind.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class MaterialFileError(MeshladarError, ValueError):
    """A material table (TOML) is unreadable or one of its entries is invalid.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class GeometryError(MeshladarError, ValueError):
    """A scene's geometry is invalid: overlapping shapes, a mesh that fails its checks.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class PhantomSpecError(MeshladarError, ValueError):
    """A phantom spec (TOML) is unreadable or one of its fields is invalid.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class ModelError(MeshladarError, NotImplementedError):
    """A BRDF lacks a method the run needs (``projected``; ``bistatic`` for a bistatic
    receiver).

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class MeshladarWarning(UserWarning):
    """Base class of meshladar's warnings: a soft precondition is not met.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """


class LobeSamplingWarning(MeshladarWarning):
    """The rays are too sparse for a coating's specular lobe on a curved part: its glint is
    undersampled (the warning names the ray spacing that resolves it).

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """


class BounceWarning(MeshladarWarning):
    """A single-bounce run of a scene whose second bounce is estimated above the threshold
    (the warning gives the estimate; ``bounces=2`` or ``"auto"`` includes it).

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """


class RecordLengthWarning(MeshladarWarning):
    """A scan's fixed record length (the sensor's ``samples``) cut off some pulses' echoes:
    their returns there are dropped (the warning counts the pulses and names the length
    that holds them).

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """


class EmptyScanWarning(MeshladarWarning):
    """A scan recorded no return: the warning says whether no pulse met the scene, the
    echoes were too weak to detect, or a fixed record length cut them, with where the
    sensor was and where the scene is.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """


class EnergyConservationWarning(MeshladarWarning):
    """A coating reflects more light than it receives at some incidence angle.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to :class:`UserWarning` unchanged.
    """
