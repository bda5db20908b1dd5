"""Per-pulse waveforms and the returns found in them.

Waveforms: sample j of a pulse's record covers [t₀ + j Δt, t₀ + (j + 1) Δt] after its
emission; each sub-ray's photoelectrons arrive at its two-way time τ = 2R/c spread by the
echo's Gaussian (the pulse and the response, :attr:`ScanSensor.sigma
<meshladar.scan.instrument.ScanSensor.sigma>`), integrated over every sample (a
difference of erfs, read from a table of the chunk's sample integrals by cubic Hermite
interpolation to 3.4e-14 of the echo's photoelectrons: :mod:`._sampling`): a record's sum
is the pulse's photoelectrons where the echo lies inside it (sub-rays arriving within
:data:`MERGE` σ of each other are spread as one, at their weighted mean time). t₀ is each
pulse's earliest echo less :data:`SUPPORT` σ (rounded down to a sample), or, for a pulse
that meets nothing, the chunk's earliest.

Detection: :mod:`.instrument`'s :class:`~meshladar.scan.instrument.Detector`.
"""

from __future__ import annotations

import math

import numpy as np

from ._peaks import centroids, find_peaks, fit_gaussians, order_returns, size_peaks
from ._sampling import (SUPPORT, accumulate, accumulate_table, echo_shape, echo_support,
                        lit_spans, matched_filter, sample_table)
from .instrument import FWHM_PER_SIGMA

__all__ = ["SUPPORT", "CENTROID_SIGMAS", "waveforms", "waveforms_with_echoes",
           "record_samples", "record_blocks", "echo_shape", "find_returns", "cfar_background",
           "Returns"]

#: A pulse's sub-rays arriving within this many σ of each other are spread as one, at
#: their photoelectron-weighted mean time: the record's sum and first moment are exact,
#: its shape off by the group's time spread squared over σ², at most (1/64)² here.
MERGE = 1.0 / 64.0
_NO_ECHOES = np.zeros((0, 2))
_NO_TABLE = (np.zeros((1, 1)), np.zeros((1, 1)), 0, 0, np.zeros((1, 1)), np.zeros((1, 1)))
#: The most Levenberg-Marquardt steps of a decomposition.
_FIT_ITERATIONS = 100
#: An echo's time is the centroid of its samples within this many σ.
CENTROID_SIGMAS = 3.0
#: Peaks closer than this many σ, whose centroid windows would overlap, are refitted
#: together (at 4 σ, two echoes 4.7 σ apart each took a share of the other's into its
#: centroid: 6 % of c τ / 2 off).
_OVERLAP_SIGMAS = 2.0 * CENTROID_SIGMAS


def _extents(spans, sigma, dt, shape, start=None):
    """Each pulse's record start (its earliest echo less the support, rounded down to a
    sample; the chunk's earliest for a pulse that meets nothing) unless given, and the
    samples its record needs to hold its echoes whole from there.

    Returns
    -------
    seen : (n,) bool numpy.ndarray
        Where something is lit.
    start : (n,) float64 numpy.ndarray
    need : (n,) float64 numpy.ndarray
    """
    first, last = spans
    seen = np.isfinite(first)
    floor = first[seen].min() if seen.any() else 0.0
    before, after = echo_support(sigma, shape)
    if start is None:
        start = np.floor((np.where(seen, first, floor) - before) / dt) * dt
    need = np.ceil((np.where(seen, last, floor) - start + after) / dt) + 1
    return seen, start, need


def record_samples(spans, start, sigma, dt, shape=None):
    """The samples each pulse's record needs to hold its echoes whole from its ``start``
    (:func:`waveforms_with_echoes`' default length, pulse by pulse; 0 where nothing is
    lit).

    Parameters
    ----------
    spans : ((n,) numpy.ndarray, (n,) numpy.ndarray)
        As :func:`record_blocks`.
    start : (n,) numpy.ndarray
        Each record's start after emission, s.
    sigma, dt, shape
        As :func:`waveforms`.

    Returns
    -------
    (n,) int64 numpy.ndarray
    """
    seen, _, need = _extents(spans, sigma, dt, shape, start)
    return np.where(seen, need, 0).astype(np.int64)


def record_blocks(spans, sigma, dt, shape, budget):
    """Runs of consecutive pulses, ``[(lo, hi), …]``, whose records (each run's as long as
    its own widest spread of echoes needs, :func:`waveforms`' default) hold at most
    ``budget`` samples in all where they can (a run of one pulse may hold more): one run
    where the chunk's records fit, else runs grown while the pulses times their widest
    record fit.

    Parameters
    ----------
    spans : ((n,) numpy.ndarray, (n,) numpy.ndarray)
        Each pulse's earliest and latest lit time (:func:`._sampling.lit_spans`: inf and
        −inf where nothing is lit).
    sigma, dt, shape
        As :func:`waveforms`.
    budget : int
        The most samples a run's records hold.

    Returns
    -------
    list of (int, int)
    """
    n = len(spans[0])
    seen, _, need = _extents(spans, sigma, dt, shape)
    if not seen.any() or n * need.max() <= budget:
        return [(0, n)]
    runs, lo, widest = [], 0, 0.0
    for p, k in enumerate(need.tolist()):
        if p > lo and (p - lo + 1) * max(widest, k) > budget:
            runs.append((lo, p))
            lo, widest = p, 0.0
        widest = max(widest, k)
    return runs + [(lo, n)]


def waveforms(tau, pe, sigma, dt, samples=None, shape=None):
    """Expected photoelectrons per sample for a chunk's pulses (module docstring).

    Parameters
    ----------
    tau, pe : (n, m) numpy.ndarray
        Each sub-ray's two-way time (s; inf on a miss) and photoelectrons (0 on a miss).
    sigma, dt : float
        The echo's σ (its RMS width) and the sample interval (s).
    samples : int, optional
        The record length; default the chunk's widest spread plus the support each side.
    shape : tuple, optional
        :func:`echo_shape`'s table for a shape that is not a Gaussian (None: Gaussian).

    Returns
    -------
    waves : (n, samples) float64
    start : (n,) float64
        Each record's start time t₀ after emission, s.
    """
    return waveforms_with_echoes(tau, pe, sigma, dt, samples, shape)[:2]


def waveforms_with_echoes(tau, pe, sigma, dt, samples=None, shape=None, spans=None):
    """:func:`waveforms`, and each record's one echo where it holds just one, whole: its
    matched-filtered samples are then read from :mod:`._sampling`'s filtered table by
    :func:`find_returns` (``echoes=``) instead of filtering the record (they agree to the
    table's 3.4e-14 of the echo's photoelectrons).

    Parameters
    ----------
    tau, pe, sigma, dt, samples, shape
        As :func:`waveforms`.
    spans : tuple, optional
        :func:`._sampling.lit_spans` of ``tau`` and ``pe`` where already found.

    Returns
    -------
    waves, start
        As :func:`waveforms`.
    echoes : (n, 2) numpy.ndarray or None
        Each record's echo, (photoelectrons, centre in samples from the record's start),
        where its sub-rays make one group whose support the record holds; (0, 0) where
        they make none or several. None where the echo's shape is not a Gaussian or no
        table is made.
    """
    tau = np.ascontiguousarray(tau, np.float64)
    pe = np.ascontiguousarray(pe, np.float64)
    # a miss, or no light: never arrives
    _, start, need = _extents(lit_spans(tau, pe) if spans is None else spans, sigma, dt,
                              shape)
    if samples is None:
        samples = max(3, int(need.max()))
    out = np.zeros((len(tau), samples))
    if shape is not None:
        accumulate_table(tau, pe, start, float(dt), float(shape[0]), float(shape[1]),
                         shape[2], out)
        return out, start, None
    tables = sample_table(float(sigma) / float(dt))
    echoes = np.empty((len(tau), 2))
    accumulate(tau, pe, start, float(dt), float(sigma), MERGE * float(sigma),
               tables or _NO_TABLE, out, echoes)
    return out, start, (echoes if tables is not None else None)


class Returns:
    """A chunk's returns, sorted by pulse then time (given in pulse order, each pulse's
    returns in any order).

    Attributes
    ----------
    pulse : numpy.ndarray
        The pulse's index within the chunk.
    time : numpy.ndarray
        Two-way time after emission, s.
    amplitude : numpy.ndarray
        Peak, photoelectrons per sample.
    width : numpy.ndarray
        FWHM, s.
    intensity : numpy.ndarray
        Photoelectrons under the echo.
    return_number, number_of_returns : numpy.ndarray
        1 for the first in time; the pulse's count.
    """

    def __init__(self, pulse, time, amplitude, width, intensity):
        pulse = np.ascontiguousarray(pulse, np.int64)
        time = np.ascontiguousarray(time, np.float64)
        order = np.empty(len(pulse), np.int64)
        self.return_number = np.empty(len(pulse), np.uint8)
        self.number_of_returns = np.empty(len(pulse), np.uint8)
        if not order_returns(pulse, time, order, self.return_number,
                             self.number_of_returns):
            raise ValueError("Returns: the pulses must come in ascending order")
        self.pulse = pulse[order]
        self.time = time[order]
        self.amplitude = amplitude[order]
        self.width = width[order]
        self.intensity = intensity[order]

    def __len__(self):
        return len(self.pulse)


def _decompose(waves, back, p, centre, s, height, sigma_samples):
    """Refit each pulse's overlapping peaks as one sum of Gaussians (in place) over its
    record less its background per sample (``back``, per peak), by a compiled
    Levenberg-Marquardt within bounds (heights ≥ 0, centres in the window, widths 0.5 to
    3 σ); a height taken to 0 is left for the caller to drop."""
    ns = waves.shape[1]
    change = np.diff(p)                                             # p is sorted
    if change.all():                                 # pulses of one peak need no refit
        return
    bounds = np.concatenate(([0], np.flatnonzero(change) + 1, [len(p)]))
    several = np.flatnonzero(np.diff(bounds) >= 2)
    for a, b in zip(bounds[several].tolist(), bounds[several + 1].tolist()):
        q = p[a]
        idx = np.arange(a, b)
        idx = idx[np.argsort(centre[idx])]
        close = np.diff(centre[idx]) < _OVERLAP_SIGMAS * sigma_samples
        if not close.any():
            continue
        lo = int(max(0, centre[idx].min() - SUPPORT * sigma_samples))
        hi = int(min(ns, centre[idx].max() + SUPPORT * sigma_samples + 1))
        x = np.arange(lo, hi) + 0.5
        y = np.ascontiguousarray(waves[q, lo:hi] - back[a], np.float64)
        k = len(idx)
        lower = np.concatenate([np.zeros(k), np.full(k, lo), np.full(k, 0.5 * sigma_samples)])
        upper = np.concatenate([np.full(k, np.inf), np.full(k, hi),
                                np.full(k, 3.0 * sigma_samples)])
        v = np.clip(np.concatenate([height[idx], centre[idx], np.full(k, sigma_samples)]),
                    lower, upper)
        fit_gaussians(x, y, v, lower, upper, _FIT_ITERATIONS)
        height[idx], centre[idx], s[idx] = v[:k], v[k:2 * k], v[2 * k:]


def cfar_background(waves, guard):
    """Each record's background per sample, estimated from the record itself (cell
    averaging).

    Parameters
    ----------
    waves : (n, samples) numpy.ndarray
        The measured records.
    guard : float
        Samples either side of a record's largest that are left out.

    Returns
    -------
    (n,) numpy.ndarray
        (the sum of each record's other samples + 1) / their number: the mean, kept off
        0 where few quiet samples would say no background at all (the threshold would
        then be a single count).
    """
    ns = waves.shape[1]
    peak = np.argmax(waves, axis=1)
    far = np.abs(np.arange(ns)[None, :] - peak[:, None]) > guard
    count = far.sum(axis=1)
    # (counts + 1) / samples: a record of few quiet samples is not taken for a background
    # of 0, whose threshold (1 count) every stray photon would cross
    return ((waves * far).sum(axis=1) + 1.0) / np.maximum(count, 1)


def find_returns(waves, start, dt, sigma, level, max_returns, decompose, background=0.0,
                 detect=None, echoes=None):
    """The returns in a chunk's waveforms (photoelectrons per sample), as :class:`Returns`
    (:mod:`.instrument`'s detection): maxima of the matched-filtered waveform whose
    largest sample within the echo's FWHM reaches ``level``, located and sized by a
    Gaussian through the filtered peak's three samples less the background per sample
    (amplitude and intensity are the echo's, above the background), and timed by the
    centroid of the samples within three σ of it, less the background (the
    maximum-likelihood time of a Gaussian echo in shot noise); with ``decompose``, peaks
    closer than six σ refitted as one sum of Gaussians over the record less its
    background, and a peak the refit takes to zero height dropped.

    Parameters
    ----------
    waves : (n, samples) numpy.ndarray
        The records, photoelectrons per sample.
    start : (n,) numpy.ndarray
        Each record's start after emission, s.
    dt, sigma : float
        The sample interval and the echo's σ, s.
    level : float or numpy.ndarray
        The threshold (broadcasting with ``waves``).
    max_returns : int
        The most returns per record.
    decompose : bool
        Refit overlapping peaks as a sum of Gaussians.
    background : float or (n,) numpy.ndarray
        Background per sample, taken off before the sizing and the centroid.
    detect : numpy.ndarray, optional
        What ``level`` applies to (default ``waves``).
    echoes : (n, 2) numpy.ndarray, optional
        Each record's one echo (:func:`waveforms_with_echoes`) where ``waves`` are the
        records as made: their filtered samples come from the filtered table; default:
        every record is filtered here.

    Returns
    -------
    Returns
        The returns found.
    """
    s = sigma / dt
    fwhm = FWHM_PER_SIGMA * s
    waves = np.ascontiguousarray(waves, np.float64)
    detect = waves if detect is None else np.ascontiguousarray(detect, np.float64)
    level = np.broadcast_to(np.asarray(level, np.float64), detect.shape)   # (a view)
    weights = matched_filter(s)
    known = _NO_ECHOES if echoes is None else np.ascontiguousarray(echoes, np.float64)
    tables = (sample_table(s) or _NO_TABLE) if echoes is not None else _NO_TABLE
    cap = len(waves) * max_returns
    p, j = np.empty(cap, np.int64), np.empty(cap, np.int64)
    f3 = np.empty((cap, 3))
    k = find_peaks(waves, known, tables, detect, level, weights, int(fwhm / 2), float(fwhm),
                   max_returns, p, j, f3)
    p, j, f3 = p[:k], j[:k], f3[:k]
    centre, s_e, height = np.empty(k), np.empty(k), np.empty(k)
    back = np.ascontiguousarray(np.broadcast_to(np.asarray(background, np.float64),
                                                (len(waves),))[p])
    # the filter has unit area: its background is the record's, taken off before sizing
    size_peaks(f3 - back[:, None], j, waves.shape[1], s, centre, s_e, height)
    centroids(waves, back, p, centre, CENTROID_SIGMAS * s, 2)
    if decompose and len(p):
        _decompose(waves, back, p, centre, s_e, height, s)
    kept = height > 0.0     # a peak the sum of Gaussians took to nothing (or no higher
    if not kept.all():      # than the background): gone
        p, centre, s_e, height = p[kept], centre[kept], s_e[kept], height[kept]
    time = start[p] + centre * dt
    return Returns(p, time, height, s_e * dt * FWHM_PER_SIGMA,
                   height * s_e * math.sqrt(2.0 * math.pi))
