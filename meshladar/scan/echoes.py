"""Per-pulse waveforms and the returns found in them.

Waveforms: sample j of a pulse's record covers [t₀ + j Δt, t₀ + (j + 1) Δt] after its
emission; each sub-ray's photoelectrons arrive at its two-way time τ = 2R/c spread by the
echo's Gaussian (the pulse and the response, :attr:`ScanSensor.sigma
<meshladar.scan.instrument.ScanSensor.sigma>`), integrated exactly over every sample (a
difference of erfs): a record's sum is the pulse's photoelectrons where the echo lies
inside it (sub-rays arriving within :data:`MERGE` σ of each other are spread as one, at
their weighted mean time). t₀ is each pulse's earliest echo less :data:`SUPPORT` σ (rounded down to a
sample), or, for a pulse that meets nothing, the chunk's earliest.

Detection: :mod:`.instrument`'s :class:`~meshladar.scan.instrument.Detector`.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.ndimage import gaussian_filter1d, maximum_filter1d
from scipy.optimize import least_squares

__all__ = ["SUPPORT", "waveforms", "find_returns", "Returns"]

#: The echo's Gaussian is cut beyond this many σ (exp(−32) of its peak).
SUPPORT = 8.0
#: A pulse's sub-rays arriving within this many σ of each other are spread as one, at
#: their photoelectron-weighted mean time: the record's sum and first moment are exact,
#: its shape off by the group's time spread squared over σ², at most (1/64)² here.
MERGE = 1.0 / 64.0
_FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))
#: Peaks closer than this many σ are refitted together.
_OVERLAP_SIGMAS = 4.0
#: An echo's time is the centroid of its samples within this many σ.
_CENTROID_SIGMAS = 3.0


@numba.njit(cache=True, nogil=True)
def _accumulate(tau, pe, start, dt, sigma, merge, out):   # pragma: no cover - compiled
    n, m = tau.shape
    ns = out.shape[1]
    s = sigma / dt
    r2 = 1.0 / (s * math.sqrt(2.0))
    order = np.empty(m, np.int64)
    for p in range(n):
        order[:] = np.argsort(tau[p])
        k = 0
        while k < m:
            # merge the sub-rays arriving within `merge` of the group's first, at their
            # photoelectron-weighted mean time (energy and first moment kept exactly)
            e = 0.0
            et = 0.0
            t0 = tau[p, order[k]]
            if not t0 < math.inf:                    # the rest missed (sorted: inf last)
                break
            while k < m and tau[p, order[k]] - t0 <= merge:
                w = pe[p, order[k]]
                if w > 0.0:
                    e += w
                    et += w * tau[p, order[k]]
                k += 1
            if e <= 0.0:
                continue
            c = (et / e - start[p]) / dt
            lo = max(0, int(math.floor(c - SUPPORT * s)))
            hi = min(ns, int(math.ceil(c + SUPPORT * s)) + 1)
            prev = math.erf((lo - c) * r2)
            for j in range(lo, hi):
                nxt = math.erf((j + 1 - c) * r2)
                out[p, j] += 0.5 * e * (nxt - prev)
                prev = nxt


def waveforms(tau, pe, sigma, dt, samples=None):
    """Expected photoelectrons per sample for a chunk's pulses (module docstring).

    Parameters
    ----------
    tau, pe : (n, m) numpy.ndarray
        Each sub-ray's two-way time (s; inf on a miss) and photoelectrons (0 on a miss).
    sigma, dt : float
        The echo's σ and the sample interval (s).
    samples : int, optional
        The record length; default the chunk's widest spread plus the support each side.

    Returns
    -------
    waves : (n, samples) float64
    start : (n,) float64
        Each record's start time t₀ after emission, s.
    """
    n = len(tau)
    lit = np.where(pe > 0, tau, np.inf)
    first, last = lit.min(axis=1), np.where(pe > 0, tau, -np.inf).max(axis=1)
    seen = np.isfinite(first)
    floor = first[seen].min() if seen.any() else 0.0
    first = np.where(seen, first, floor)
    last = np.where(seen, last, floor)
    start = np.floor((first - SUPPORT * sigma) / dt) * dt
    if samples is None:
        spread = (last - start + SUPPORT * sigma) / dt
        samples = max(3, int(math.ceil(spread.max())) + 1)
    out = np.zeros((n, samples))
    _accumulate(np.where(pe > 0, tau, np.inf), np.ascontiguousarray(pe, np.float64), start,
                float(dt), float(sigma), MERGE * float(sigma), out)
    return out, start


class Returns:
    """A chunk's returns: pulse index (within the chunk), time after emission (s),
    amplitude (photoelectrons per sample), FWHM width (s), intensity (photoelectrons),
    return number (1 = first in time) and number of returns of its pulse."""

    def __init__(self, pulse, time, amplitude, width, intensity):
        order = np.lexsort((time, pulse))
        self.pulse = pulse[order]
        self.time = time[order]
        self.amplitude = amplitude[order]
        self.width = width[order]
        self.intensity = intensity[order]
        counts = np.bincount(self.pulse, minlength=0)
        self.number_of_returns = counts[self.pulse].astype(np.uint8) if len(self.pulse) else \
            np.zeros(0, np.uint8)
        first = np.searchsorted(self.pulse, self.pulse, side="left")
        self.return_number = (np.arange(len(self.pulse)) - first + 1).astype(np.uint8)

    def __len__(self):
        return len(self.pulse)


def _suppress(p, j, separation):
    """Keep, pulse by pulse from the strongest down, the maxima farther than
    ``separation`` samples from every stronger one kept (p sorted, strongest first)."""
    keep = np.ones(len(p), bool)
    starts = np.r_[0, np.nonzero(np.diff(p))[0] + 1, len(p)]
    for a, b in zip(starts[:-1], starts[1:]):
        if b - a < 2:
            continue
        kept = []
        for i in range(a, b):
            if any(abs(j[i] - j[k]) <= separation for k in kept):
                keep[i] = False
            else:
                kept.append(i)
    return keep


def _candidates(waves, reach, max_returns, separation):
    """Local maxima of ``waves`` where ``reach`` is at least 0, farther than
    ``separation`` samples from a stronger one: (pulse, sample), the strongest
    ``max_returns`` of each pulse."""
    w = waves
    left = np.concatenate([np.full((len(w), 1), -np.inf), w[:, :-1]], axis=1)
    right = np.concatenate([w[:, 1:], np.full((len(w), 1), -np.inf)], axis=1)
    p, j = np.nonzero((reach >= 0) & (w > 0) & (w >= left) & (w > right))
    amp = w[p, j]
    order = np.lexsort((-amp, p))
    p, j = p[order], j[order]
    keep = _suppress(p, j, separation)
    p, j = p[keep], j[keep]
    rank = np.arange(len(p)) - np.searchsorted(p, p, side="left")
    keep = rank < max_returns
    return p[keep], j[keep]


def _interpolate(waves, p, j, sigma_samples):
    """A Gaussian through each peak's three samples: offset (samples), σ (samples), height."""
    ns = waves.shape[1]
    a = waves[p, np.maximum(j - 1, 0)]
    b = waves[p, j]
    c = waves[p, np.minimum(j + 1, ns - 1)]
    tiny = 1e-300
    la, lb, lc = (np.log(np.maximum(x, tiny)) for x in (a, b, c))
    curv = la - 2.0 * lb + lc
    good = (a > 0) & (c > 0) & (curv < 0) & (j > 0) & (j < ns - 1)
    curv_safe = np.where(good, curv, -1.0)
    delta = np.where(good, np.clip(0.5 * (la - lc) / curv_safe, -0.5, 0.5), 0.0)
    s = np.where(good, np.sqrt(-1.0 / curv_safe), sigma_samples)
    height = np.where(good, np.exp(lb - 0.25 * (la - lc) * delta), b)
    return delta, s, height


def _decompose(waves, p, centre, s, height, sigma_samples):
    """Refit each pulse's overlapping peaks as one sum of Gaussians (in place)."""
    ns = waves.shape[1]
    bounds = np.r_[0, np.nonzero(np.diff(p))[0] + 1, len(p)]        # p is sorted
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a < 2:
            continue
        q = p[a]
        idx = np.arange(a, b)
        idx = idx[np.argsort(centre[idx])]
        close = np.diff(centre[idx]) < _OVERLAP_SIGMAS * sigma_samples
        if not close.any():
            continue
        lo = int(max(0, centre[idx].min() - SUPPORT * sigma_samples))
        hi = int(min(ns, centre[idx].max() + SUPPORT * sigma_samples + 1))
        x = np.arange(lo, hi) + 0.5
        y = waves[q, lo:hi]
        k = len(idx)

        def model(v):
            h, mu, sd = v[:k], v[k:2 * k], v[2 * k:]
            return (h[:, None] * np.exp(-0.5 * ((x[None, :] - mu[:, None]) / sd[:, None]) ** 2)
                    ).sum(axis=0)

        v0 = np.concatenate([height[idx], centre[idx], np.full(k, sigma_samples)])
        lower = np.concatenate([np.zeros(k), np.full(k, lo), np.full(k, 0.5 * sigma_samples)])
        upper = np.concatenate([np.full(k, np.inf), np.full(k, hi),
                                np.full(k, 3.0 * sigma_samples)])
        fit = least_squares(lambda v: model(v) - y, np.clip(v0, lower, upper),
                            bounds=(lower, upper))
        height[idx], centre[idx], s[idx] = fit.x[:k], fit.x[k:2 * k], fit.x[2 * k:]


def _centroid(waves, p, centre, half, rounds=2):
    """Each echo's time (samples): the centroid of ``waves`` within ``half`` samples of
    ``centre`` (the samples at the window's edges weighed by the part of them inside it, so
    the window is symmetric about the centre wherever it falls between samples),
    re-centred ``rounds`` times (vectorised over echoes)."""
    ns = waves.shape[1]
    k = np.arange(-int(math.ceil(half)) - 1, int(math.ceil(half)) + 2)
    for _ in range(rounds):
        idx = np.floor(centre).astype(np.int64)[:, None] + k[None, :]
        x = idx + 0.5
        # each sample weighed by the part of it inside the window: no jump as it moves
        part = np.clip(half + 0.5 - np.abs(x - centre[:, None]), 0.0, 1.0)
        part = np.where((idx >= 0) & (idx < ns), part, 0.0)
        w = part * waves[p[:, None], np.clip(idx, 0, ns - 1)]
        total = w.sum(axis=1)
        ok = total > 0
        centre = np.where(ok, (w * x).sum(axis=1) / np.where(ok, total, 1.0), centre)
    return centre


def find_returns(waves, start, dt, sigma, level, max_returns, decompose, background=0.0,
                 detect=None):
    """The returns in a chunk's waveforms (photoelectrons per sample), as :class:`Returns`
    (:mod:`.instrument`'s detection): maxima of the matched-filtered waveform whose
    largest sample within the echo's FWHM reaches ``level``, located and sized by a
    Gaussian through the filtered peak's three samples, and timed by the centroid of the
    samples within :data:`_CENTROID_SIGMAS` σ of it, less the ``background`` per sample
    (the maximum-likelihood time of a Gaussian echo in shot noise). ``level`` is a number
    or an array like ``waves``; ``detect`` (default ``waves``) is what it applies to (a
    Geiger-mode histogram, whose level follows its armed shots)."""
    s = sigma / dt
    fwhm = _FWHM_PER_SIGMA * s
    filtered = gaussian_filter1d(waves, s, axis=1, mode="constant", truncate=4.0)
    margin = (waves if detect is None else detect) - level
    reach = maximum_filter1d(margin, 2 * int(fwhm / 2) + 1, axis=1, mode="constant",
                             cval=-np.inf)
    p, j = _candidates(filtered, reach, max_returns, fwhm)
    delta, s_f, height_f = _interpolate(filtered, p, j, s * math.sqrt(2.0))
    centre = _centroid(waves - background, p, j + 0.5 + delta, _CENTROID_SIGMAS * s)
    area = height_f * s_f * math.sqrt(2.0 * math.pi)        # the filter has unit area
    s_e = np.sqrt(np.maximum(s_f ** 2 - s ** 2, 0.25 * s ** 2))
    height = area / (s_e * math.sqrt(2.0 * math.pi))
    if decompose and len(p):
        _decompose(waves, p, centre, s_e, height, s)
    time = start[p] + centre * dt
    return Returns(p, time, height, s_e * dt * _FWHM_PER_SIGMA,
                   height * s_e * math.sqrt(2.0 * math.pi))
