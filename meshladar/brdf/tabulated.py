"""A measured monostatic BRDF, tabulated in angle."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._validate import check_flag, check_name, finite_array
from ..errors import ParameterError
from .base import BRDF

__all__ = ["Tabulated"]


#: The largest BRDF value a table may hold (sr⁻¹): far above any real glint's peak, and
#: small enough that the weights, sums and squares computed from it stay finite.
MAX_BRDF = 1e12


@dataclass(frozen=True, eq=False)
class Tabulated(BRDF, builtin=True):
    """A measured monostatic BRDF: F(θ) sampled at angles ``theta_deg``.

    ================  =====  ==================  ========================================
    name              unit   valid range         meaning
    ================  =====  ==================  ========================================
    theta_deg         deg    0 ... 90, strictly  sample angles from the normal
                             increasing
    values            1/sr   >= 0, finite        F at each angle (or F·cos θ)
    projected_values  -      bool                ``values`` are F·cos θ, not F
    name              -      any str             a label; not in equality
    ================  =====  ==================  ========================================

    ``theta_deg`` must increase strictly from 0 to 90 (degrees); ``values`` are F in 1/sr
    (or, with ``projected_values=True``, F·cos θ: give that form when F grows toward
    grazing incidence, as glossy coatings' does). Between samples F·cos θ is interpolated
    linearly in θ. Monostatic only.

    Parameters
    ----------
    theta_deg : (k,) array_like, degrees
        Sample angles from the normal, k ≥ 2, finite, strictly increasing, the first
        exactly 0 and the last exactly 90. Stored as a read-only float64 copy.
    values : (k,) array_like, 1/sr
        F (or F·cos θ) at each angle, finite, in [0, 1e12]. Stored as a read-only float64
        copy, as given.
    projected_values : bool, keyword-only, default False
        ``values`` are F·cos θ, not F. With False, F·cos θ at 90° is taken as exactly 0
        whatever the last value.
    name : str or None, keyword-only, default None
        A label; not part of equality.

    Raises
    ------
    ParameterError
        When ``name`` is neither a str nor None, ``projected_values`` is not a bool,
        ``theta_deg`` or ``values`` holds non-finite or non-real numbers, ``theta_deg`` is
        not 1-D with at least 2 angles, ``values`` does not have its shape, ``theta_deg``
        does not increase strictly from exactly 0 to exactly 90, or a value is outside
        [0, 1e12].
    """

    theta_deg: np.ndarray
    values: np.ndarray
    projected_values: bool = field(default=False, kw_only=True)
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        check_name(self.name)
        check_flag("projected_values", self.projected_values)
        t = np.array(finite_array("theta_deg", self.theta_deg))          # copies: the user's
        v = np.array(finite_array("values", self.values))                # arrays stay theirs
        if t.ndim != 1 or t.size < 2:
            raise ParameterError(f"theta_deg must be a 1-D array of at least 2 angles; got "
                                 f"shape {t.shape}")
        if v.shape != t.shape:
            raise ParameterError(f"values must have theta_deg's shape {t.shape}; got {v.shape}")
        if t[0] != 0.0 or t[-1] != 90.0 or np.any(np.diff(t) <= 0):
            raise ParameterError(f"theta_deg must increase strictly from 0 to 90 degrees; got "
                                 f"{t[0]:g} ... {t[-1]:g}" + (" (not increasing)" if
                                                             np.any(np.diff(t) <= 0) else ""))
        if np.any(v < 0) or np.any(v > MAX_BRDF):
            k = int(np.argmax((v < 0) | (v > MAX_BRDF)))
            raise ParameterError(f"values must be in [0, {MAX_BRDF:g}] (per sr: a mirror-like "
                                 f"glint peaks near 1e6); got {v[k]:g} at {t[k]:g} degrees")
        weight = v.copy() if self.projected_values else v * np.cos(np.deg2rad(t))
        if not self.projected_values:
            weight[-1] = 0.0                                    # F cos θ at exactly 90°
        for k, a in (("theta_deg", t), ("values", v), ("_weight", weight)):
            a = np.array(a, dtype=np.float64)
            a.flags.writeable = False
            object.__setattr__(self, k, a)

    def __eq__(self, other):
        return (type(other) is Tabulated and np.array_equal(self.theta_deg, other.theta_deg)
                and np.array_equal(self._weight, other._weight))

    __hash__ = None

    def projected(self, cos_theta, sin_theta):
        """F(θ; −θ)·cos θ in 1/sr, interpolated linearly in θ between the samples.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; values < 0 are clamped to 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``. θ is read as
            atan2(sin θ, max(cos θ, 0)), in degrees, and looked up in ``theta_deg``.

        Returns
        -------
        ndarray
            F·cos θ in 1/sr, float64, of the inputs' broadcast shape.
        """
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        theta = np.degrees(np.arctan2(np.asarray(sin_theta, np.float64), c))
        return np.interp(theta, self.theta_deg, self._weight)

    @property
    def angular_scales(self):
        step = float(np.min(np.diff(np.deg2rad(self.theta_deg))))
        return (step, step)

    def lobe_width(self):
        """The angle where F, interpolated, first falls to a quarter of F(0) (a glint
        measured at normal incidence); None where F(0) = 0 or F never falls that far
        before 90° (a diffuse or grazing-bright table).

        F at each sample is the table's F·cos θ over cos θ; the sample at 90° is not
        searched, and between the two samples that bracket F(0)/4, F is interpolated
        linearly in θ.

        Returns
        -------
        float or None
            The angle in radians, or None.
        """
        t = np.deg2rad(self.theta_deg)
        f = self._weight / np.maximum(np.cos(t), 1e-300)            # F at each sample
        below = np.flatnonzero(f[:-1] <= 0.25 * f[0])
        if f[0] <= 0 or below.size == 0:
            return None
        k = int(below[0])                       # f[k - 1] > f[0]/4 >= f[k]
        return float(np.interp(0.25 * f[0], [f[k], f[k - 1]], [t[k], t[k - 1]]))

    def describe(self) -> dict:
        """A JSON-serialisable description: the model's name and its parameters.

        Returns
        -------
        dict
            ``"model"`` ("Tabulated"), ``"name"``, ``"theta_deg"`` and ``"values"`` (as
            stored, as lists) and ``"projected_values"``.
        """
        return {"model": "Tabulated", "name": self.name, "theta_deg": self.theta_deg.tolist(),
                "values": self.values.tolist(), "projected_values": self.projected_values}
