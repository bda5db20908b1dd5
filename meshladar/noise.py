"""The receiver's noise (Goodman's statistics) and its seeded draws.

Per sample of mean signal s (photoelectrons) and background b = (background_rate +
dark_rate)·Δt: the speckled intensity I ~ Gamma(M, s/M) for M speckle cells per resolution
cell (variance s²/M); the photoelectron count N ~ Poisson(I + b); an APD of mean gain G and
excess noise factor F multiplies N by a gamma-distributed gain (mean GN, variance
G²N(F − 1)); the digitiser rounds to ``bits`` over ``full_scale``. So the mean is G(s + b)
and the variance G²(F(s + b) + s²/M) (before quantisation). A sample the digitiser cannot
hold reads its top code, (2**bits − 1)·full_scale/2**bits: the draws' clipped fraction
(:meth:`Noise.clipped_fraction`, the fraction at the top code) is warned about with a
:class:`~meshladar.errors.MeshladarWarning` that names the full scale that would hold them,
and :func:`meshladar.io.save_waveforms` records it in the saved noise. Samples are independent: one
speckle cell per sample. :meth:`meshladar.waveforms.Waveforms.realise` draws them on a
noiseless waveform.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from ._validate import check_count, check_real, check_seed, check_size
from .errors import MeshladarWarning, ParameterError, user_stacklevel

__all__ = ["Noise", "draw_noise"]


#: The highest background or dark rate taken, photoelectrons per second: 1e15 (a
#: second's dwell still draws within numpy's Poisson range, ~9e18).
MAX_RATE = 1e15
#: The largest mean count per cell a draw takes: numpy's Poisson stops near 9e18, and a
#: speckle draw can reach hundreds of times its mean.
MAX_MEAN_COUNT = 1e16
#: The highest gain (and excess noise factor) taken: 1e9, beyond any APD or PMT, so that
#: gain × counts stays finite.
MAX_GAIN = 1e9


@dataclass(frozen=True)
class Noise:
    """The receiver's noise (module docstring).

    Parameters
    ----------
    speckle_cells : float, optional
        M, speckle cells per resolution cell (≥ 1; 1 is fully developed speckle); None: no
        speckle.
    background_rate, dark_rate : float
        Background (sky, scattered light) and dark counts, photoelectrons per second
        (at most :data:`MAX_RATE`, 1e15).
    excess_noise_factor : float
        APD excess noise factor F ≥ 1 (1: a noiseless gain; at most :data:`MAX_GAIN`).
    gain : float
        Mean gain G (output units per photoelectron; at most :data:`MAX_GAIN`, 1e9).
    bits : int, optional
        Digitiser resolution; with ``full_scale`` (output units), samples are rounded to
        full_scale / 2**bits and clipped to [0, full_scale): a draw that clips warns
        (:class:`~meshladar.errors.MeshladarWarning`, with the clipped fraction and the
        full scale that would avoid it).
    full_scale : float, optional
        The digitiser's full scale, output units (> 0); given together with ``bits``.

    Raises
    ------
    ParameterError
        When a parameter is outside the ranges above (``gain`` must be > 0, ``bits`` an
        integer in [1, 32]), or only one of ``bits`` and ``full_scale`` is given.
    """

    speckle_cells: float | None = None
    background_rate: float = 0.0
    dark_rate: float = 0.0
    excess_noise_factor: float = 1.0
    gain: float = 1.0
    bits: int | None = None
    full_scale: float | None = None

    def __post_init__(self):
        if self.speckle_cells is not None:
            object.__setattr__(self, "speckle_cells", check_real(
                "speckle_cells", self.speckle_cells, low=1.0))
        for name in ("background_rate", "dark_rate"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), low=0.0,
                                                      high=MAX_RATE))
        object.__setattr__(self, "excess_noise_factor", check_real(
            "excess_noise_factor", self.excess_noise_factor, low=1.0, high=MAX_GAIN))
        object.__setattr__(self, "gain", check_real("gain", self.gain, low=0.0,
                                                    low_open=True, high=MAX_GAIN))
        if (self.bits is None) != (self.full_scale is None):
            raise ParameterError("quantisation needs both bits and full_scale; got "
                                 f"bits={self.bits!r}, full_scale={self.full_scale!r}")
        if self.bits is not None:
            object.__setattr__(self, "bits", check_count("bits", self.bits))
            if self.bits > 32:
                raise ParameterError(f"bits must be at most 32; got {self.bits}")
            object.__setattr__(self, "full_scale", check_real(
                "full_scale", self.full_scale, low=0.0, low_open=True))

    def mean(self, signal, dt):
        """Expected output per sample for mean signal (photoelectrons), before
        quantisation.

        Parameters
        ----------
        signal : float or array_like
            Mean signal s per sample, photoelectrons.
        dt : float
            Sample interval Δt, s: the background b = (background_rate + dark_rate)·Δt.

        Returns
        -------
        float or numpy.ndarray
            G (s + b), output units, the shape of ``signal``.
        """
        return self.gain * (signal + (self.background_rate + self.dark_rate) * dt)

    def variance(self, signal, dt):
        """Variance per sample, before quantisation: G² (F (s + b) + s²/M).

        Parameters
        ----------
        signal : float or array_like
            Mean signal s per sample, photoelectrons.
        dt : float
            Sample interval Δt, s: the background b = (background_rate + dark_rate)·Δt.

        Returns
        -------
        float or numpy.ndarray
            The variance, output units squared, the shape of ``signal``; the s²/M term is
            0 without speckle (``speckle_cells`` None).
        """
        b = (self.background_rate + self.dark_rate) * dt
        speckle = 0.0 if self.speckle_cells is None else signal ** 2 / self.speckle_cells
        return self.gain ** 2 * (self.excess_noise_factor * (signal + b) + speckle)

    def describe(self):
        """The parameters as a JSON-serialisable dict (as :func:`meshladar.io.save_waveforms`
        stores them).

        Returns
        -------
        dict
            ``speckle_cells``, ``background_rate_per_s``, ``dark_rate_per_s``,
            ``excess_noise_factor``, ``gain``, ``bits`` and ``full_scale``.
        """
        return {"speckle_cells": self.speckle_cells,
                "background_rate_per_s": self.background_rate,
                "dark_rate_per_s": self.dark_rate,
                "excess_noise_factor": self.excess_noise_factor, "gain": self.gain,
                "bits": self.bits, "full_scale": self.full_scale}

    def clipped_fraction(self, draws) -> float:
        """The fraction of ``draws`` (output units) at the digitiser's top code,
        (2**bits − 1)·full_scale/2**bits, where every sample beyond full scale lands;
        0 without quantisation.

        Parameters
        ----------
        draws : array_like
            Noise realisations, output units (e.g. from
            :meth:`meshladar.waveforms.Waveforms.realise`).

        Returns
        -------
        float
            The fraction of ``draws`` at or above the top code, in [0, 1]; 0.0 without
            quantisation (``bits`` None) or for empty ``draws``.
        """
        draws = np.asarray(draws, dtype=np.float64)
        if self.bits is None or draws.size == 0:
            return 0.0
        top = (2 ** self.bits - 1) * (self.full_scale / 2.0 ** self.bits)
        return float(np.mean(draws >= top))


#: The peak memory of :func:`draw_noise`, in bytes per drawn sample: the output (8), the
#: integer counts it is made from (8), the gamma draw of the excess noise (8) and a mask (1),
#: rounded up; measured with tracemalloc in tests/values/test_noise_memory.py.
DRAW_PEAK_BYTES = 32


def draw_noise(noise, signal, dwell, n, seed):
    """``n`` realisations, shape ``(n, *signal.shape)``, of ``noise`` on mean ``signal``
    (photoelectrons per cell), each cell integrating background and dark counts over
    ``dwell`` seconds (module docstring). Seeded through numpy's default generator.
    Refused before drawing when its peak memory (:data:`DRAW_PEAK_BYTES` per sample) would
    pass meshladar's allocation cap, or a cell's mean count :data:`MAX_MEAN_COUNT`.

    Parameters
    ----------
    noise : Noise
        The receiver's noise.
    signal : array_like
        Mean signal per cell, photoelectrons; negative values are drawn as 0.
    dwell : float
        Integration time of each cell, s (the sample interval Δt).
    n : int
        Number of realisations (not checked here: :meth:`Waveforms.realise
        <meshladar.waveforms.Waveforms.realise>` checks it).
    seed : int, sequence of int or None
        Seed of :func:`numpy.random.default_rng` (None: fresh entropy).

    Returns
    -------
    (n, ...) numpy.ndarray
        float64 draws (``...`` the shape of ``signal``) in output units, gain ×
        photoelectrons; when ``noise`` quantises, rounded to multiples of full_scale /
        2**bits and clipped to [0, top code].

    Raises
    ------
    ParameterError
        When ``seed`` is not None, a non-negative integer or a non-empty sequence of them;
        when the draws would need more than meshladar's allocation cap; or when the largest
        mean count per cell (signal plus background and dark counts over ``dwell``) is over
        :data:`MAX_MEAN_COUNT` or not a number.

    Warns
    -----
    MeshladarWarning
        When some quantised draws clip at the digitiser's top code.

    References
    ----------
    J. W. Goodman, *Statistical Optics*, Wiley (1985) (integrated speckle intensity
    Gamma(M, s/M) for M speckle cells; photocounts Poisson given the intensity).
    """
    rng = np.random.default_rng(check_seed("seed", seed))
    shape = (n,) + np.shape(signal)
    check_size("n", float(n) * max(1, int(np.prod(np.shape(signal)))), DRAW_PEAK_BYTES,
               f"{n} realisations of {np.shape(signal)} samples", "draw fewer at a time")
    b = _background(noise, signal, dwell)
    s = np.broadcast_to(np.maximum(signal, 0.0), shape)
    if noise.speckle_cells is not None:
        m = noise.speckle_cells
        intensity = rng.gamma(m, 1.0, size=shape)
        intensity *= s / m                              # in place: one array, not three
        intensity += b
    else:
        intensity = s + b
    counts = rng.poisson(intensity)
    del intensity
    out = counts.astype(np.float64)
    del counts                                          # freed before the gain's draws
    out = _apd_gain(rng, noise, out)
    if noise.bits is not None:
        lsb = noise.full_scale / 2.0 ** noise.bits
        peak = float(out.max()) if out.size else 0.0
        out = np.clip(np.floor(out / lsb + 0.5), 0, 2 ** noise.bits - 1) * lsb
        _warn_clipped(noise, noise.clipped_fraction(out), peak)
    return out


def _background(noise, signal, dwell):
    """The background and dark counts per cell over ``dwell``, b, once the largest mean
    count per cell (``signal``'s largest plus b) is checked against :data:`MAX_MEAN_COUNT`."""
    b = (noise.background_rate + noise.dark_rate) * dwell
    top = (float(np.max(signal)) if np.size(signal) else 0.0) + b
    if not top <= MAX_MEAN_COUNT:
        raise ParameterError(f"the largest mean count per cell would be {top:.3g} "
                             f"photoelectrons (signal plus background and dark counts over the "
                             f"dwell), beyond the {MAX_MEAN_COUNT:.0e} the draws take: check "
                             "the signal's scale, the rates and the dwell")
    return b


def _apd_gain(rng, noise, counts):
    """The APD's output for the photoelectron ``counts`` (float64, reused in place): each
    count N times a gamma-distributed gain (mean GN, variance G²N(F − 1)), or GN exactly
    for a noiseless gain (F = 1)."""
    f = noise.excess_noise_factor
    if f > 1.0:
        fired = counts > 0
        counts /= f - 1.0                               # the gamma shapes, in place
        counts[~fired] = 1.0
        return np.where(fired, rng.gamma(counts, noise.gain * (f - 1.0)), 0.0)
    counts *= noise.gain
    return counts


def _warn_clipped(noise, fraction, peak):
    """Warn when a fraction of the draws sits at the top code; the full scale that would
    hold ``peak`` (the largest unquantised draw) below it, rounded up to 2 digits."""
    if fraction <= 0.0:
        return
    need = peak * 2.0 ** noise.bits / (2.0 ** noise.bits - 1.5)
    step = 10.0 ** (math.floor(math.log10(need)) - 1)
    need = math.ceil(need / step) * step
    warnings.warn(f"{100 * fraction:.3g} % of the noisy samples clip at the digitiser's "
                  f"full scale ({noise.full_scale:g}; they read its top code): give "
                  f"full_scale >= {need:.3g} (the largest draw is {peak:.4g}), or a lower "
                  "gain", MeshladarWarning, stacklevel=user_stacklevel())
