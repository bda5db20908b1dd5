"""Boundary checks shared by the engine: each raises and returns nothing, or returns the
cleaned value. Messages name the argument, the value received and what is valid."""

from __future__ import annotations

import math
import os
from numbers import Real

import numpy as np

from .errors import ParameterError
from .precision import ANGLE_TOL_DEG

__all__: list[str] = []

#: The largest array meshladar allocates on a user's say-so (4 GiB: a sixth of this
#: project's 24 GiB machines); beyond it a request is refused before allocating, naming what
#: to reduce, instead of dying in numpy's MemoryError or the kernel's OOM killer.
MAX_ARRAY_BYTES = 4 * 2**30


#: The longest quotation of a user's value in a message (characters): an array or a
#: 400-digit number is cut, so the message stays one readable line.
MAX_QUOTE = 80


def short(value) -> str:
    """``repr(value)`` on one line, cut to :data:`MAX_QUOTE` characters."""
    text = " ".join(repr(value).split())
    return text if len(text) <= MAX_QUOTE else text[: MAX_QUOTE - 3] + "..."


def check_real(name: str, value, *, low: float | None = None, high: float | None = None,
               low_open: bool = False, high_open: bool = False) -> float:
    """Return ``value`` as a float after checking that it is a finite real in the range.

    ``low``/``high`` bound the range, closed unless ``low_open``/``high_open``.
    """
    if isinstance(value, bool) or not isinstance(value, (Real, np.floating, np.integer)):
        raise ParameterError(f"{name} must be a real number; got {short(value)}")
    try:
        x = float(value)
    except OverflowError:          # an integer beyond float64 (a 400-digit table entry)
        x = math.inf if value > 0 else -math.inf
    lo = "(" if low_open or low is None else "["       # an infinite end is never in it
    hi = ")" if high_open or high is None else "]"
    valid = f"{lo}{'-inf' if low is None else f'{low:g}'}, {'inf' if high is None else f'{high:g}'}{hi}"
    if not math.isfinite(x):
        raise ParameterError(f"{name} must be finite and in {valid}; got {x!r}")
    if low is not None and (x < low or (low_open and x == low)):
        raise ParameterError(f"{name} must be in {valid}; got {x!r}")
    if high is not None and (x > high or (high_open and x == high)):
        raise ParameterError(f"{name} must be in {valid}; got {x!r}")
    return x


def check_choice(name: str, value, choices: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise naming them."""
    if not isinstance(value, str) or value not in choices:
        raise ParameterError(f"{name} must be one of {choices}; got {short(value)}")
    return value


def finite_array(name: str, value) -> np.ndarray:
    """Return ``value`` as a float64 array, raising if any element is NaN or infinite."""
    if value is None:
        raise ParameterError(f"{name} must be an array of real numbers; got None")
    try:
        if np.iscomplexobj(value):
            raise ParameterError(f"{name} must be real numbers; got a complex array (take "
                                 "its real part, magnitude or power yourself: which is meant "
                                 "is not for meshladar to guess)")
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(f"{name} must be an array of real numbers; got {short(value)}") from exc
    if not np.all(np.isfinite(a)):
        bad = float(a[~np.isfinite(a)].ravel()[0])
        idx = np.argwhere(~np.isfinite(a))[0]
        where = f" at index {tuple(int(i) for i in idx)}" if a.ndim else ""
        raise ParameterError(f"{name} must be finite; got {bad!r}{where}")
    return a


def readonly_copy(a) -> np.ndarray:
    """A read-only float64 copy (stage outputs are immutable)."""
    a = np.array(a, dtype=np.float64, copy=True)
    a.flags.writeable = False
    return a


#: The largest count any option takes (2^53, the last integer float64 holds exactly): a
#: larger one cannot be a size, an iteration count or a number of draws.
MAX_COUNT = 2 ** 53


def check_count(name: str, value, low: int = 1, high: int = MAX_COUNT) -> int:
    """Return ``value`` as an int after checking it is an integer in [low, high] (bools
    refused)."""
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer))
            or value < low):
        raise ParameterError(f"{name} must be an integer >= {low}; got {short(value)}")
    if value > high:
        raise ParameterError(f"{name} must be an integer in [{low}, {high}]; got "
                             f"{short(value)}")
    return int(value)


def unit_vectors(name: str, value) -> np.ndarray:
    """``value`` as finite (..., 3) float64 directions, each normalised to unit length."""
    a = finite_array(name, value)
    if a.shape[-1:] != (3,):
        raise ParameterError(f"{name} must have shape (..., 3); got {a.shape}")
    norm = np.linalg.norm(a, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise ParameterError(f"{name} must be non-zero direction vectors; got a zero vector")
    return a / norm


def azimuths_deg(view_vectors) -> np.ndarray:
    """The azimuths, in degrees about z, of (n, 3) view vectors: the angles of their views."""
    return np.degrees(np.arctan2(view_vectors[:, 1], view_vectors[:, 0]))


def check_views_agree(angles_deg, view_vectors) -> None:
    """Refuse view angles (degrees) that differ from their unit view vectors' azimuths by
    more than :data:`meshladar.precision.ANGLE_TOL_DEG` (vectors along ±z excepted): the
    analytic and pixel models and 2-D FBP read the angles, the mesh model and 3-D
    reconstruction the vectors, so a contradiction would give each its own views."""
    azimuth = azimuths_deg(view_vectors)
    off = np.abs((angles_deg - azimuth + 180.0) % 360.0 - 180.0)
    off = np.where(np.hypot(view_vectors[:, 0], view_vectors[:, 1]) > 0, off, 0.0)
    if np.any(off > ANGLE_TOL_DEG):
        k = int(np.argmax(off))
        raise ParameterError(
            f"angles_deg and view_vectors disagree: view {k} has angle "
            f"{float(angles_deg[k]):g} deg but vector {view_vectors[k].tolist()} (azimuth "
            f"{float(azimuth[k]):g} deg); give one of them")


def check_weights(weights, shape, *, expected, sign, zero) -> np.ndarray:
    """``weights`` as a finite float64 array of ``shape``, every one ≥ 0 and some > 0; the
    messages read "weights must be {expected}; got shape …", "weights must be {sign}; got
    {value} at index {index} (of shape …)" and "weights are all zero (shape …): {zero}"."""
    w = finite_array("weights", weights)
    if w.shape != tuple(shape):
        raise ParameterError(f"weights must be {expected}; got shape {w.shape}")
    if np.any(w < 0):
        idx = tuple(int(i) for i in np.argwhere(w < 0)[0])
        raise ParameterError(f"weights must be {sign}; got {w[idx]:g} at index "
                             f"{idx[0] if len(idx) == 1 else idx} (of shape {w.shape})")
    if not np.any(w > 0):
        raise ParameterError(f"weights are all zero (shape {w.shape}): {zero}")
    return w


def views_agree(angles_deg, view_vectors) -> bool:
    """False only where ``view_vectors`` (n, 3) and ``angles_deg`` (n,) can be compared
    and :func:`check_views_agree` refuses them (a file's stored views)."""
    if view_vectors is None:
        return True
    a, v = np.asarray(angles_deg, dtype=float), np.asarray(view_vectors, dtype=float)
    if a.ndim != 1 or v.shape != (a.size, 3):
        return True                           # the Sinogram names what is wrong
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = v / np.linalg.norm(v, axis=1, keepdims=True)
    try:
        check_views_agree(a, unit)
    except ParameterError:
        return False
    return True


def check_size(name: str, count, bytes_each: int, what: str, reduce: str) -> None:
    """Refuse an allocation of ``count`` items of ``bytes_each`` over MAX_ARRAY_BYTES."""
    need = float(count) * bytes_each
    if need > MAX_ARRAY_BYTES:
        raise ParameterError(f"{name}: {what} would need {need / 2**30:.3g} GiB, more than the "
                             f"{MAX_ARRAY_BYTES / 2**30:g} GiB meshladar allocates at once; "
                             f"{reduce}")


def check_seed(name: str, value):
    """Return ``value`` as an int, a list of ints (numpy's entropy sequences, as
    ``default_rng([seed, chunk])``) or None (fresh entropy), after checking that it is a
    non-negative integer or a non-empty sequence of them (numpy takes any size): the one
    validator behind every ``seed=``."""
    if value is None:
        return None
    if isinstance(value, (list, tuple, np.ndarray)) and len(value) and all(
            _seed_int(v) for v in np.asarray(value, dtype=object).ravel()):
        return [int(v) for v in np.asarray(value, dtype=object).ravel()]
    if not _seed_int(value):
        raise ParameterError(f"{name} must be None or a non-negative integer; got {short(value)}")
    return int(value)


def _seed_int(v):
    return not isinstance(v, (bool, np.bool_)) and isinstance(v, (int, np.integer)) and v >= 0


def check_name(value) -> None:
    """A label (``name=``) must be a string or None."""
    if value is not None and not isinstance(value, str):
        raise ParameterError(f"name must be a string or None; got {short(value)}")


def check_flag(name: str, value) -> bool:
    """Return ``value`` if it is a bool (numpy's included), else raise."""
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False; got {short(value)}")
    return bool(value)


def check_path(name: str, value):
    """``value`` as a path string (str or os.PathLike, not empty), else a ParameterError."""
    if isinstance(value, (str, os.PathLike)):
        path = os.fspath(value)
        if isinstance(path, str) and path:
            return path
    raise ParameterError(f"{name} must be a file path; got {short(value)}")


def check_sinogram(name: str, value):
    """``value`` if it is a meshladar.Sinogram, else a ParameterError.

    Kept for the importers of one release; new code uses
    :func:`meshladar.sinogram.check_sinogram`. The foundation does not import the record
    (no import circle): the class is recognised by its qualified name along the MRO."""
    if not any(c.__module__ == "meshladar.sinogram" and c.__qualname__ == "Sinogram"
               for c in type(value).__mro__):
        raise ParameterError(f"{name} must be a meshladar.Sinogram; got {type(value).__name__}")
    return value
