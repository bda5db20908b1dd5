"""A rigid target's motion (:class:`Motion`), the value that Doppler returns are binned by
(:mod:`meshladar.forward.resolved`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_real, finite_array
from .errors import ParameterError

__all__ = ["Motion"]


def _vector(name, value):
    a = finite_array(name, value)
    if a.shape != (3,):
        raise ParameterError(f"{name} must be a 3-vector; got shape {a.shape}")
    return tuple(float(x) for x in a)



@dataclass(frozen=True)
class Motion:
    """A rigid target's motion, for Doppler.

    Parameters
    ----------
    omega : (3,) float
        Rotation vector Ω (rad/s): the axis times the rate, right-handed (a turntable
        turning counter-clockwise seen from above at 0.1 rad/s: (0, 0, 0.1)).
    center : (3,) float
        A point on the rotation axis (m; default the origin).
    velocity : (3,) float
        Translation V (m/s).
    wavelength : float
        λ (m; default 1.064e-6), > 0.

    Raises
    ------
    ParameterError
        When ``omega``, ``center`` or ``velocity`` is not three finite numbers, or
        ``wavelength`` is not a finite number > 0.
    """

    omega: tuple = (0.0, 0.0, 0.0)
    center: tuple = (0.0, 0.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    wavelength: float = 1.064e-6

    def __post_init__(self):
        for name in ("omega", "center", "velocity"):
            object.__setattr__(self, name, _vector(name, getattr(self, name)))
        object.__setattr__(self, "wavelength", check_real("wavelength", self.wavelength,
                                                          low=0.0, low_open=True))

    def doppler(self, points, w):
        """f_D (Hz) of ``points`` (k, 3) seen from view ``w``: 2 (V + Ω × (p − c))·w / λ.

        Parameters
        ----------
        points : (k, 3) array_like
            Points p on the target, m.
        w : (3,) array_like
            The view vector (from the scene toward the ladar; a unit vector, not
            normalised here).

        Returns
        -------
        (k,) numpy.ndarray
            Doppler shift of each point, Hz: positive for a point moving toward the ladar.
        """
        rel = np.asarray(points, np.float64) - np.asarray(self.center)
        vel = np.cross(np.asarray(self.omega), rel) + np.asarray(self.velocity)
        return 2.0 * (vel @ np.asarray(w, np.float64)) / self.wavelength

    def describe(self):
        """Every parameter, with its unit in its name (for result files).

        Returns
        -------
        dict
            ``omega_rad_per_s``, ``center_m``, ``velocity_m_per_s`` (lists of three
            floats) and ``wavelength_m``.
        """
        return {"omega_rad_per_s": list(self.omega), "center_m": list(self.center),
                "velocity_m_per_s": list(self.velocity), "wavelength_m": self.wavelength}

