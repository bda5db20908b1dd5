"""Geiger-mode detection: single-photon avalanche pixels, histograms over many shots, and
the Coates correction.

Each pattern pulse is ``shots`` laser shots from the same pose. In a shot, sample j of the
record carries mean primary events λ_j = η s_j + b (η the detection efficiency, s_j the
echo's expected photoelectrons, b the background and dark counts per sample); an armed
pixel fires in sample j with probability 1 − exp(−λ_j) (its first event avalanches) and
is then blind for the ``dead_time`` after that sample (rounded up to samples; the default, infinite, is one
detection per shot, the classic Geiger-mode APD). The first photons block the later ones:
at high signal the histogram of detection times piles up early.

Coates' correction (Coates 1968) undoes it: with h_j detections in sample j over K shots
and D_j the shots dead in sample j (those that fired in the dead time before it: all
earlier samples for an infinite dead time), λ̂_j = −ln(1 − h_j / (K − D_j)); where every
armed shot fired (h_j = K − D_j) the estimate is capped at ln(K − D_j + 1), finite.
Returns are then found in K λ̂ (counts per sample as a linear-mode receiver would see them
over K shots, background K b) by the linear-mode detector, its threshold applied to the
histogram itself: in sample j, the Poisson threshold of the armed shots' background
counts (K − D_j)(1 − e^{−b}), so late samples with few armed shots raise no false alarms.

Reference: P. B. Coates, "The correction for photon 'pile-up' in the measurement of
radiative lifetimes", J. Phys. E 1, 878 (1968).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from .._validate import check_count, check_real
from ..errors import ParameterError

__all__ = ["GeigerMode", "fire", "coates", "blind_shots", "FIRE_BLOCK"]


@dataclass(frozen=True)
class GeigerMode:
    """A Geiger-mode array's pixels (module docstring).

    Parameters
    ----------
    shots : int
        Laser shots per pattern pulse, histogrammed together (1 to 1e6; default 100).
    dead_time : float
        Seconds a pixel stays blind after it fires (> 0; default inf: once per shot).
    detection_efficiency : float
        The probability that a signal photoelectron sets off an avalanche, in (0, 1]
        (default 1: the sensor's quantum efficiency already counts photoelectrons).
    """

    shots: int = 100
    dead_time: float = math.inf
    detection_efficiency: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "shots", check_count("shots", self.shots, high=10 ** 6))
        if self.dead_time != math.inf:
            try:
                check_real("dead_time", self.dead_time, low=0.0, low_open=True, high=1.0)
            except ParameterError:
                raise ParameterError(f"dead_time must be in (0, 1] s, or inf (a pixel that "
                                     f"fires once per shot, the default); got "
                                     f"{self.dead_time!r}") from None
            object.__setattr__(self, "dead_time", float(self.dead_time))
        object.__setattr__(self, "detection_efficiency", check_real(
            "detection_efficiency", self.detection_efficiency, low=0.0, low_open=True,
            high=1.0))

    def dead_samples(self, dt):
        """The dead time in samples.

        Parameters
        ----------
        dt : float
            The sample interval, s.

        Returns
        -------
        int
            Samples, rounded up (at least 1), or 0 for an infinite dead time.
        """
        return 0 if self.dead_time == math.inf else max(1, math.ceil(self.dead_time / dt))

    def describe(self) -> dict:
        """The parameters, with units in their names.

        Returns
        -------
        dict
            ``shots``, ``dead_time_s`` and ``detection_efficiency``.
        """
        return {"shots": self.shots, "dead_time_s": self.dead_time,
                "detection_efficiency": self.detection_efficiency}


#: Shot-samples (rows × shots × samples) a compiled call of :func:`fire` takes at most
#: (about 0.1 s here): between calls Ctrl-C and SIGTERM are heard.
FIRE_BLOCK = 1 << 24


@numba.njit(cache=True)
def _fire(lam, shots, dead, seed, out):                 # pragma: no cover - compiled
    if seed >= 0:                    # the stream's start; a later block continues it
        np.random.seed(seed)
    n, ns = lam.shape
    for p in range(n):
        for _ in range(shots):
            j = 0
            while j < ns:
                # the next avalanche: the first sample where the events since j pass an
                # exponential draw (exact for independent Poisson samples)
                need = -math.log(1.0 - np.random.random())
                acc = 0.0
                while j < ns:
                    acc += lam[p, j]
                    if acc >= need:
                        break
                    j += 1
                if j >= ns:
                    break
                out[p, j] += 1
                if dead == 0:
                    break
                j += dead + 1                           # blind for the dead samples after j


def fire(lam, shots, dead, seed):
    """Detection histograms of ``shots`` shots (module docstring).

    Parameters
    ----------
    lam : (n, samples) array_like
        Mean primary events per sample.
    shots : int
        Shots per record.
    dead : int
        Dead samples after a detection (0: one detection per shot).
    seed : int
        The compiled generator's seed (≥ 0). The records are drawn in blocks of at most
        :data:`FIRE_BLOCK` shot-samples, one stream (the same draws as one block), so an
        interrupt is heard between blocks.

    Returns
    -------
    (n, samples) numpy.ndarray
        Detections per sample, int64.
    """
    lam = np.ascontiguousarray(lam, np.float64)
    out = np.zeros(lam.shape, np.int64)
    rows = max(1, FIRE_BLOCK // max(1, int(shots) * lam.shape[1]))
    for lo in range(0, len(lam), rows):    # one stream, in blocks: the same draws
        _fire(lam[lo:lo + rows], int(shots), int(dead), int(seed) if lo == 0 else -1,
              out[lo:lo + rows])
    return out


def blind_shots(hist, dead):
    """The shots blind in each sample: those that fired in the ``dead`` samples before it.

    Parameters
    ----------
    hist : (n, samples) array_like
        Detections per sample.
    dead : int
        Dead samples (0: all earlier samples, one detection per shot).

    Returns
    -------
    (n, samples) numpy.ndarray
        D_j, float64.
    """
    h = np.asarray(hist, np.float64)
    before = np.cumsum(h, axis=1) - h                     # detections before each sample
    if dead == 0:
        return before
    lagged = np.concatenate([np.zeros((len(h), dead)), before], axis=1)[:, :h.shape[1]]
    return before - lagged


def coates(hist, shots, dead):
    """Coates' estimate λ̂ (n, samples) of the mean events per sample from detection
    histograms (module docstring).

    Parameters
    ----------
    hist : (n, samples) array_like
        Detections per sample over ``shots`` shots.
    shots : int
        K, the shots histogrammed.
    dead : int
        Dead samples after a detection (0: one detection per shot).

    Returns
    -------
    (n, samples) numpy.ndarray
        λ̂, float64, finite.
    """
    h = np.asarray(hist, np.float64)
    armed = shots - blind_shots(h, dead)
    frac = np.divide(h, armed, out=np.zeros_like(h), where=armed > 0)
    full = (h >= armed) & (armed > 0)
    lam = -np.log1p(-np.where(full, 0.0, frac))
    return np.where(full, np.log(armed + 1.0), lam)
