"""The registry of built-in models, and the line it draws: a built-in model's outputs are
trusted as they come, a user's model's are checked.

A model registers itself by subclassing :class:`~meshladar.brdf.BRDF` with
``builtin=True`` (``class GGX(BRDF, builtin=True)``): :data:`MODELS` maps its name to its
class. :func:`projected_weight` is the door through which the forward models call a
coating's :meth:`~meshladar.brdf.BRDF.projected`; it passes a built-in model's output
through and checks a user's (shape, finite, ≥ 0). The names are also importable from
:mod:`meshladar.brdf.base` and :mod:`meshladar.brdf`.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from ..errors import ParameterError

__all__ = ["MODELS", "is_builtin", "projected_weight"]

#: The built-in models by class name, filled by each model's file as it is defined
#: (``class Name(BRDF, builtin=True)``); read-only.
_REGISTRY: dict = {}
MODELS = MappingProxyType(_REGISTRY)


def is_builtin(model) -> bool:
    """True when ``model`` is an instance of a registered built-in model (not a subclass
    of one): its outputs are trusted and not checked.

    Parameters
    ----------
    model : object
        Any object; only its exact type is looked at.

    Returns
    -------
    bool
        True when ``type(model)`` is the class registered in :data:`MODELS` under its
        class name; False for a user's model, a subclass of a built-in model, or a
        non-BRDF.
    """
    return MODELS.get(type(model).__name__) is type(model)


def projected_weight(m, cos_theta, sin_theta):
    """``m.projected(cos θ, sin θ)`` as a float64 array of the inputs' shape, checked for a
    user's model: finite and non-negative, else a ParameterError naming the class.

    The protocol's domain is cos θ ≥ 0 with (cos θ, sin θ) a unit pair: a cos θ below 0
    (a direction below the horizon, where a forward model weighs the surface as at grazing
    or discards the weight) is clamped to 0 and its sin θ set to 1, so that a model sees
    θ = π/2 whether it reads the cosine, the sine or the angle atan2(sin θ, cos θ). Pairs
    with cos θ ≥ 0 pass unchanged.

    Parameters
    ----------
    m : BRDF
        The model whose :meth:`BRDF.projected` is called.
    cos_theta : array_like
        cos θ of the monostatic incidence angle; values < 0 are clamped to 0.
    sin_theta : array_like
        sin θ, broadcasting with ``cos_theta``; set to 1 where cos θ < 0.

    Returns
    -------
    ndarray
        F(θ; −θ)·cos θ in 1/sr. For a user's model, a read-only float64 array of the
        inputs' broadcast shape (``np.broadcast_to`` of the model's output); for a built-in
        model (:func:`is_builtin`), its output as returned, unchecked.

    Raises
    ------
    ParameterError
        When a user's model returns something that does not convert to real numbers of the
        inputs' shape, or a value that is not finite or is negative.
    ModelError
        When the class does not define :meth:`BRDF.projected`.
    """
    cos_theta, sin_theta = _grazing_below_horizon(cos_theta, sin_theta)
    out = m.projected(cos_theta, sin_theta)
    if is_builtin(m):
        return out
    shape = np.broadcast(np.asarray(cos_theta), np.asarray(sin_theta)).shape
    try:
        out = np.broadcast_to(np.asarray(out, dtype=np.float64), shape)
    except (TypeError, ValueError):
        raise ParameterError(f"{type(m).__name__}.projected must return real numbers of the "
                             f"inputs' shape {shape}; got {type(out).__name__} of shape "
                             f"{np.shape(out)}") from None
    bad = ~np.isfinite(out) | (out < 0)
    if bad.any():
        k = np.flatnonzero(bad.ravel())[0]
        raise ParameterError(f"{type(m).__name__}.projected must be finite and non-negative; "
                             f"got {float(out.ravel()[k]):.6g} at cos theta = "
                             f"{float(np.broadcast_to(cos_theta, shape).ravel()[k]):.6g}")
    return out


def _grazing_below_horizon(cos_theta, sin_theta):
    """(max(cos θ, 0), sin θ) with sin θ = 1 where cos θ < 0: the clamped pair stays a unit
    pair (θ = π/2). Inputs with no cos θ < 0 pass through as they are."""
    below = np.asarray(cos_theta) < 0
    if below.any():
        sin_theta = np.where(below, 1.0, sin_theta)
    return np.maximum(cos_theta, 0.0), sin_theta
