"""The BRDF protocol every forward model accepts (:class:`BRDF`) and the check that a value
follows it (:func:`check_brdf`).

A coating defines ``projected(cos_theta, sin_theta)``, its monostatic weight F(θ; −θ)·cos θ,
and inherits ``monostatic``; a bistatic receiver needs ``bistatic`` as well. Built-in models
register themselves by subclassing with ``builtin=True`` (``class GGX(BRDF, builtin=True)``):
:data:`MODELS` maps their names to their classes, and their outputs are trusted, while a
user's model is checked (shape, finite, ≥ 0) by :func:`projected_weight`. The registry and
that check live in :mod:`meshladar.brdf.registry`, :func:`material_table` (the compiled
kernel's table) in :mod:`meshladar.brdf.kernel_table`; all four names are importable from
here as well.

Conventions
-----------
* Angles are polar angles from the outward surface normal, in radians. Directions point
  away from the surface (toward the source, toward the receiver).
* Every function here depends on an angle only through its cosine and the magnitude of its
  sine: it is even and 2π-periodic in θ. Where a direction is below the horizon
  (cos θ < 0) the BRDF is exactly 0. At the horizon itself (cos θ = 0, reachable with
  direction vectors) F is evaluated as at θ = fl(π/2), whose cosine is 6.1e-17, so it stays
  finite; the projected weight F·cos θr is continuous up to and including θr = π/2.
* BRDF values are in 1/sr.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._validate import check_flag, finite_array, unit_vectors
from ..errors import ModelError, ParameterError
from ..precision import COS_HORIZON as _COS_HORIZON
from ._shared import _cos_sin, _cos_sin_vec, _out, _safe_divide
from .kernel_table import material_table
from .registry import _REGISTRY, MODELS, is_builtin, projected_weight

__all__ = ["BRDF", "MODELS", "is_builtin", "projected_weight", "check_brdf", "material_table"]


class BRDF:
    """The BRDF protocol: what a coating must give for every forward model to use it.

    A subclass defines :meth:`projected`, the monostatic weight F(θ; −θ)·cos θ of the
    paper's Eq. 8 on arrays of (cos θ, sin θ) with cos θ ≥ 0 (0 below the horizon, finite
    up to and including θ = π/2). Everything else derives from it: :meth:`monostatic` for
    users, :meth:`value` (F itself) for the mesh engine. A bistatic receiver needs
    :meth:`bistatic` too. ``kernel_params`` (a row for the compiled SR kernel) and
    ``angular_scales`` (the narrowest features, for the analytic model's quadrature) are
    optional speed and accuracy hints.

    A built-in model registers itself in :data:`MODELS` by subclassing with
    ``builtin=True``; a user's subclass is not registered, and its outputs are checked.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> class Matte(ml.brdf.BRDF):
    ...     def projected(self, cos_theta, sin_theta):
    ...         return 0.3 / np.pi * np.maximum(cos_theta, 0.0)
    >>> round(Matte().monostatic(0.0), 4)
    0.0955
    """

    #: Row of the compiled SR kernel's material table, or None (the engine then calls
    #: :meth:`value` on arrays: slower, same result).
    kernel_params = None

    #: (near normal, near grazing): the angular widths, in radians, of the fastest
    #: variation of F·cos θ near θ = 0 and θ = π/2, or None where it is smooth. The analytic
    #: model grades its quadrature panels to them.
    angular_scales = (None, None)

    name = None

    def __init_subclass__(cls, /, *, builtin=False, **kwargs):
        super().__init_subclass__(**kwargs)
        if builtin:
            _REGISTRY[cls.__name__] = cls

    def lobe_width(self):
        """The angular half-width, in radians of the monostatic incidence angle θ, of the
        coating's specular (glint) lobe: about where the lobe falls to a quarter of its
        peak at normal incidence (GGX's α, Sandford-Robertson's e, Phong's
        arccos(4^(−1/n))/2). None for a coating without a specular lobe (Lambertian, a
        diffuse-only Sandford-Robertson) and, by default, for a user's model, which may
        define it. The mesh model compares it with the normal change between neighbouring
        rays and warns when the rays cannot resolve the lobe
        (:mod:`meshladar.forward.sampling`).

        Returns
        -------
        float or None
            The half-width in radians; the base class returns None.
        """
        return None

    def projected(self, cos_theta, sin_theta):
        """F(θ; −θ)·cos θ in 1/sr for arrays cos θ ≥ 0 and sin θ = sqrt(1 − cos²θ) ≥ 0:
        every forward model passes unit pairs, (0, 1) where a direction is below the
        horizon, so a model may read the cosine, the sine or the angle.

        The one method a subclass must define; the base class only raises.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ (from the outward normal), ≥ 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``.

        Returns
        -------
        ndarray
            F(θ; −θ)·cos θ in 1/sr, finite and ≥ 0, of the inputs' broadcast shape (a
            subclass's return; :func:`projected_weight` checks a user's model's).

        Raises
        ------
        ModelError
            Always, from the base class: a subclass that does not define it cannot be
            evaluated.

        References
        ----------
        Jin & Levine (2009), Eq. 8.
        """
        raise ModelError(f"{type(self).__name__} must define projected(cos_theta, "
                         "sin_theta), the monostatic F·cos θ (meshladar.brdf.BRDF)")

    def value(self, cos_theta, sin_theta):
        """F(θ; −θ) in 1/sr: the projected weight over cos θ (cos(fl(π/2)) at the horizon),
        0 below it.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ. Where it is < 0 (below the horizon)
            the result is 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``.

        Returns
        -------
        ndarray
            F(θ; −θ) in 1/sr: :func:`projected_weight` divided by max(cos θ, cos(fl(π/2))),
            of the inputs' broadcast shape (float64).

        Raises
        ------
        ParameterError
            When a user's model's :meth:`projected` returns values of the wrong shape,
            non-finite or negative values (from :func:`projected_weight`).
        ModelError
            When the class does not define :meth:`projected`.
        """
        c = np.asarray(cos_theta, np.float64)
        p = projected_weight(self, c, sin_theta)          # (0, 1) below the horizon
        return np.where(c >= 0, p / np.maximum(c, _COS_HORIZON), 0.0)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr in 1/sr from the cosines and sines of θi, θr and the half
        vector's polar angle; 0 below either horizon. Optional.

        Parameters
        ----------
        cos_i, sin_i : array_like
            Cosine and sine (≥ 0) of θi, the polar angle of the direction to the source.
        cos_r, sin_r : array_like
            Cosine and sine (≥ 0) of θr, the polar angle of the direction to the receiver.
        cos_h, sin_h : array_like
            Cosine and sine (≥ 0) of the polar angle of the half vector that bisects the
            two directions (the glint angle α). All six broadcast together.

        Returns
        -------
        ndarray
            F(w_i, w_r)·cos θr in 1/sr (a subclass's return; the base class has none).

        Raises
        ------
        ModelError
            Always, from the base class: a model without a bistatic evaluation cannot be
            used with a bistatic receiver.
        """
        raise ModelError(f"{type(self).__name__} has no bistatic evaluation: define "
                         "bistatic() to use it with a bistatic receiver")

    def bistatic_value(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r) in 1/sr (the bistatic weight over cos θr).

        Parameters
        ----------
        cos_i, sin_i : array_like
            Cosine and sine (≥ 0) of θi, the polar angle of the direction to the source.
        cos_r, sin_r : array_like
            Cosine and sine (≥ 0) of θr, the polar angle of the direction to the receiver.
        cos_h, sin_h : array_like
            Cosine and sine (≥ 0) of the half vector's polar angle. All six broadcast
            together.

        Returns
        -------
        ndarray
            :meth:`bistatic` divided by max(cos θr, cos(fl(π/2))); 0 where cos θi < 0 or
            cos θr < 0.

        Raises
        ------
        ModelError
            When the class does not define :meth:`bistatic`.
        """
        p = self.bistatic(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h)
        return np.where((cos_i >= 0) & (cos_r >= 0), p / np.maximum(cos_r, _COS_HORIZON), 0.0)

    def monostatic(self, theta, *, projected=False):
        """F(θ; −θ) (or F·cos θ with ``projected=True``) for incidence angles θ in radians,
        0 below the horizon; a float for a scalar θ.

        Parameters
        ----------
        theta : array_like, radians
            Incidence angle from the outward normal; must be finite. Only cos θ and |sin θ|
            enter; the result is 0 where cos θ < 0.
        projected : bool, keyword-only, default False
            Return F(θ)·cos θ (:meth:`projected`) instead of F (:meth:`value`).

        Returns
        -------
        ndarray or float
            In 1/sr, the shape of ``theta``; a Python float for a scalar ``theta``.

        Raises
        ------
        ParameterError
            When ``theta`` is not finite real numbers, ``projected`` is not a bool, or a
            user's model returns values of the wrong shape, non-finite or negative.
        ModelError
            When the class does not define :meth:`projected`.
        """
        c, s = _cos_sin(theta, "theta")
        check_flag("projected", projected)
        out = projected_weight(self, c, s) if projected else self.value(c, s)
        return _out(np.where(c >= 0, out, 0.0), theta)

    def evaluate(self, incident, reflected, normal=(0.0, 0.0, 1.0), *, projected=False):
        """F(w_i, w_r) for arbitrary (bistatic) directions, in 1/sr.

        Parameters
        ----------
        incident : (..., 3) array_like
            Direction from the surface toward the source; need not be unit length.
        reflected : (..., 3) array_like
            Direction from the surface toward the receiver.
        normal : (..., 3) array_like, default +z
            Outward surface normal. All three broadcast together.
        projected : bool, keyword-only
            Return F·cos θr, finite up to and including θr = π/2.

        Returns
        -------
        (...) ndarray
            0 where either direction is below the horizon.

        Raises
        ------
        ParameterError
            When a direction is not finite, not of shape (..., 3) or zero, the three do not
            broadcast together, or ``projected`` is not a bool.
        ModelError
            When the class does not define :meth:`bistatic`.
        """
        check_flag("projected", projected)
        w_i = unit_vectors("incident", incident)
        w_r = unit_vectors("reflected", reflected)
        n = unit_vectors("normal", normal)
        try:
            np.broadcast_shapes(w_i.shape, w_r.shape, n.shape)
        except ValueError:
            raise ParameterError(f"incident, reflected and normal must broadcast together; got "
                                 f"shapes {w_i.shape}, {w_r.shape}, {n.shape}") from None
        cos_i, sin_i = _cos_sin_vec(w_i, n)
        cos_r, sin_r = _cos_sin_vec(w_r, n)
        half = w_i + w_r
        norm = np.linalg.norm(half, axis=-1)
        # Opposite directions (both on the horizon): α = π/2
        cos_a = _safe_divide(np.einsum("...k,...k->...", half, n), norm, 0.0)
        sin_a = _safe_divide(np.linalg.norm(np.cross(half, n), axis=-1), norm, 1.0)
        return self._evaluate_cs(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected)

    def _evaluate_cs(self, cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected):
        if projected:
            visible = (cos_i >= 0) & (cos_r >= 0)
            return np.where(visible, self.bistatic(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a),
                            0.0)
        return self.bistatic_value(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a)

    def evaluate_angles(self, theta_i, theta_r, delta_phi=0.0, *, projected=False):
        """F for polar angles θi, θr and relative azimuth Δφ = φr − φi, in 1/sr.

        Δφ = 0 with θr = θi is the monostatic geometry; Δφ = π with θr = θi is the mirror
        (Snell) direction. Angles in radians, broadcast together.

        The directions are built about the normal +z: w_i = (sin θi, 0, cos θi) and
        w_r = (sin θr cos Δφ, sin θr sin Δφ, cos θr), then passed to :meth:`evaluate`.

        Parameters
        ----------
        theta_i : array_like, radians
            Polar angle of the direction to the source; must be finite.
        theta_r : array_like, radians
            Polar angle of the direction to the receiver; must be finite.
        delta_phi : array_like, radians, default 0.0
            Relative azimuth φr − φi; must be finite.
        projected : bool, keyword-only, default False
            Return F·cos θr instead of F.

        Returns
        -------
        ndarray or float
            In 1/sr, of the angles' broadcast shape; 0 where either direction is below the
            horizon; a Python float when all three angles are scalars.

        Raises
        ------
        ParameterError
            When an angle is not finite real numbers or ``projected`` is not a bool.
        ValueError
            When the angles do not broadcast together.
        ModelError
            When the class does not define :meth:`bistatic`.
        """
        ti = finite_array("theta_i", theta_i)
        tr = finite_array("theta_r", theta_r)
        dp = finite_array("delta_phi", delta_phi)
        zero = np.zeros(np.broadcast(ti, tr, dp).shape)
        w_i = np.stack([np.sin(ti) + zero, zero, np.cos(ti) + zero], axis=-1)
        w_r = np.stack([np.sin(tr) * np.cos(dp) + zero, np.sin(tr) * np.sin(dp) + zero,
                        np.cos(tr) + zero], axis=-1)
        return _out(self.evaluate(w_i, w_r, projected=projected), theta_i, theta_r, delta_phi)

    def describe(self) -> dict:
        """A JSON-serialisable description: the model's name and its parameters.

        Returns
        -------
        dict
            ``"model"`` (the class name), ``"name"`` (the label, or None) and, for a
            dataclass, every other field by name, arrays as lists. A user's model that is
            not a dataclass gives only ``"model"`` and ``"name"``.
        """
        params = ({f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                   if f.name != "name"} if dataclasses.is_dataclass(self) else {})
        return {"model": type(self).__name__, "name": self.name,
                **{k: v.tolist() if isinstance(v, np.ndarray) else v
                   for k, v in params.items()}}


def check_brdf(name, value):
    """``value`` if it follows the BRDF protocol, else a ParameterError naming ``name``.

    Parameters
    ----------
    name : str
        The argument's name, quoted in the error message.
    value : object
        The candidate coating.

    Returns
    -------
    BRDF
        ``value`` itself, unchanged.

    Raises
    ------
    ParameterError
        When ``value`` is not an instance of :class:`BRDF`.
    ModelError
        When its class does not define :meth:`BRDF.projected`.
    """
    if not isinstance(value, BRDF):
        hint = ""
        if isinstance(value, str):          # a coating's name, as the command line takes
            hint = (f" {value!r}: a coating by name is meshladar.materials.PAPER[name] "
                    "(list(meshladar.materials.PAPER) names the packaged ones), or a "
                    "table's meshladar.materials.load_table(path)[name]")
        raise ParameterError(f"{name} must be a meshladar.brdf.BRDF ({', '.join(MODELS)} "
                             f"or a subclass); got {type(value).__name__}{hint}")
    if type(value).projected is BRDF.projected:
        raise ModelError(f"{name}: {type(value).__name__} must define projected(cos_theta, "
                         "sin_theta), the monostatic F·cos θ (meshladar.brdf.BRDF)")
    return value
