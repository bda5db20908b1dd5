"""The pulse shapes :func:`meshladar.waveforms.receive` convolves a sinogram's bins with:
the transmitted pulse and the receiver's impulse response, a Gaussian or a user's sampled
shape, each of unit area; and their kernels on receive's fine time grid.

:mod:`meshladar.waveforms` re-exports the public names (``meshladar.waveforms.GaussianPulse``),
where they are documented.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import check_real, finite_array, readonly_copy
from .errors import ParameterError

__all__ = ["GaussianPulse", "SampledPulse", "MAX_PULSE_S", "MIN_PULSE_S"]

#: The longest pulse, response or sample interval taken (s): a second is 3e8 m of range.
MAX_PULSE_S = 1.0
#: The shortest (s): an attosecond, far below any laser's; subnormal widths overflowed.
MIN_PULSE_S = 1e-18
#: A Gaussian pulse or response is cut where it falls below exp(−CUT²/2) of its peak.
_GAUSS_CUT = 8.0
#: FWHM = 2 sqrt(2 ln 2) σ
_FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


@dataclass(frozen=True)
class GaussianPulse:
    """A Gaussian pulse (or impulse response) of full width at half maximum ``fwhm`` (s),
    centred on t = 0, unit area.

    Parameters
    ----------
    fwhm : float
        Full width at half maximum, s, in [:data:`MIN_PULSE_S`, :data:`MAX_PULSE_S`]
        (1e-18 s to 1 s).

    Raises
    ------
    ParameterError
        When ``fwhm`` is not a finite real number in that range.
    """

    fwhm: float

    def __post_init__(self):
        object.__setattr__(self, "fwhm", check_real("fwhm", self.fwhm, low=MIN_PULSE_S,
                                                    high=MAX_PULSE_S))

    @property
    def support(self):
        """(start, end) in s outside which it is zero."""
        h = _GAUSS_CUT * self.fwhm / _FWHM_PER_SIGMA
        return -h, h

    def cdf(self, t):
        """The fraction of the pulse's area before time ``t``.

        Parameters
        ----------
        t : float or array_like
            Time, s, from the pulse's centre.

        Returns
        -------
        numpy.ndarray
            Φ(t / σ), σ = fwhm / (2 sqrt(2 ln 2)), Φ the standard normal CDF (not cut at
            :attr:`support`), the shape of ``t``.
        """
        from scipy.special import ndtr

        return ndtr(np.asarray(t, np.float64) * _FWHM_PER_SIGMA / self.fwhm)

    def describe(self):
        """The parameters, with units in their names (for result files).

        Returns
        -------
        dict
            ``{"kind": "gaussian", "fwhm_s": fwhm}``.
        """
        return {"kind": "gaussian", "fwhm_s": self.fwhm}


@dataclass(frozen=True)
class SampledPulse:
    """A user's pulse shape (or impulse response): ``samples`` ≥ 0 of its power at
    ``interval`` (s) spacing from ``start`` (s), held constant over each interval;
    normalised to unit area here.

    Parameters
    ----------
    samples : (n,) array_like
        The pulse's power in each interval: finite, ≥ 0, not all zero. Stored as a
        read-only float64 copy divided by its sum (each interval's fraction of the area).
    interval : float
        Sample spacing, s, in [:data:`MIN_PULSE_S`, :data:`MAX_PULSE_S`].
    start : float
        Time of the first sample's leading edge, s (default 0.0); any finite real.

    Raises
    ------
    ParameterError
        When ``samples`` is not a non-empty 1-D array of finite non-negative numbers with
        one above zero, or ``interval`` or ``start`` is out of range or not finite.
    """

    samples: np.ndarray
    interval: float
    start: float = 0.0

    def __post_init__(self):
        x = finite_array("samples", self.samples)
        if x.ndim != 1 or x.size == 0 or np.any(x < 0) or not np.any(x > 0):
            raise ParameterError("samples must be a non-empty 1-D array of non-negative "
                                 "numbers, not all zero")
        object.__setattr__(self, "samples", readonly_copy(x / x.sum()))
        object.__setattr__(self, "interval", check_real("interval", self.interval,
                                                        low=MIN_PULSE_S, high=MAX_PULSE_S))
        object.__setattr__(self, "start", check_real("start", self.start))

    @property
    def support(self):
        return self.start, self.start + self.interval * self.samples.size

    def cdf(self, t):
        """The fraction of the pulse's area before time ``t``.

        Parameters
        ----------
        t : float or array_like
            Time, s (the same origin as ``start``).

        Returns
        -------
        float or numpy.ndarray
            The cumulative sum of ``samples`` interpolated linearly between the sample
            edges ``start + k·interval``: 0 before ``start``, 1 after the last edge; the
            shape of ``t``.
        """
        edges = self.start + self.interval * np.arange(self.samples.size + 1)
        return np.interp(t, edges, np.concatenate([[0.0], np.cumsum(self.samples)]))

    def describe(self):
        """The parameters, with units in their names (for result files).

        Returns
        -------
        dict
            ``kind`` ("samples"), ``interval_s``, ``start_s`` and ``samples`` (the
            normalised samples, as a list).
        """
        return {"kind": "samples", "interval_s": self.interval, "start_s": self.start,
                "samples": self.samples.tolist()}


def _check_shape(name, value):
    if value is not None and not isinstance(value, (GaussianPulse, SampledPulse)):
        raise ParameterError(f"{name} must be a GaussianPulse, a SampledPulse or None; got "
                             f"{type(value).__name__}")
    return value


def _kernel(shape, dt):
    """Unit-sum kernel of ``shape`` on cells of width dt: index 0 is the cell [k0 dt,
    (k0 + 1) dt); returns (kernel, k0)."""
    if shape is None:
        return np.ones(1), 0
    lo, hi = shape.support
    k0, k1 = math.floor(lo / dt), math.ceil(hi / dt)
    cdf = shape.cdf(np.arange(k0, k1 + 1) * dt)
    kern = np.diff(cdf)
    return kern / kern.sum(), k0
