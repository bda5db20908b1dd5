"""What the receiver records: a sinogram's bins turned into time waveforms (the transmitted
pulse, the receiver's impulse response, a digitiser), and noise realisations of them
(photon counting, speckle, background and dark counts, APD excess noise, quantisation).

Trace once, receive many times: :func:`receive` works on any :class:`Sinogram` (best one of
received power, ``radiometry="power"``), and :meth:`Waveforms.realise` draws any number of
seeded noise realisations from one noiseless waveform.

Time. A bin at range r (scene units, metres) returns at two-way time t = 2(r + D)/c, with D
the sensor's standoff (recorded in the sinogram's ``info["sensor"]``), or D = 0 for a
ladar at infinity (t then counts from the echo of range 0). With the sensor aimed at a
point other than the origin, t is the two-way time less 2 aim·w / c (ranges are
R − D − aim·w, :class:`meshladar.sensor.Sensor`).

Energy. Each bin's content is spread uniformly over its time interval on a fine grid
(``oversample`` cells per digitiser sample), convolved with the pulse and the impulse
response (each normalised to unit area on that grid), and summed into digitiser samples:
every step conserves the total, so a view's samples sum to its bins (to rounding, 1e-12).

Noise: :class:`meshladar.noise.Noise` (Goodman's statistics; its module docstring).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import plotting
from ._summary import table, text
# the pulse shapes (their own module), re-exported here, where they always were
from ._pulses import (MAX_PULSE_S, MIN_PULSE_S, GaussianPulse, SampledPulse, _check_shape,
                      _kernel)
from ._validate import (check_count, check_real, check_seed, check_size, finite_array,
                        readonly_copy)
from .errors import ParameterError
from .noise import Noise, draw_noise
from .sensor import LIMITS as SENSOR_LIMITS
from .sensor import SPEED_OF_LIGHT
from .sinogram import TYPED_INFO_KEYS, Sinogram, check_sinogram, split_info

__all__ = ["GaussianPulse", "SampledPulse", "Waveforms", "receive"]

#: Digitiser rates receive accepts, Hz: one sample per second to one per attosecond (the
#: pulses' shortest), so its time grid stays finite.
SAMPLE_RATE_RANGE = (1.0, 1e18)
#: receive's peak memory per fine cell of (views + 1) rows of (window + kernels): the FFT
#: convolution's padded copies and spectra (measured ≤ 140 B; a margin above).
RECEIVE_PEAK_BYTES = 192
#: The most fine cells per digitiser sample receive's convolutions take (its default is 8).
MAX_OVERSAMPLE = 1024
#: The most samples Waveforms.detection_probability draws in all (n pulses × the
#: waveforms' samples, signal and noise alone): about a minute's draws.
MAX_DETECTION_DRAWS = 10 ** 10


@dataclass(frozen=True, eq=False)
class Waveforms:
    """Sampled waveforms of many views: what a digitiser records per pulse.

    ``values`` (n_views, n_samples): the signal in each sample (its integral over the
    sample: photoelectrons when the sinogram counted them, else the sinogram's units);
    ``time_edges`` (n_samples + 1,) in s, two-way time; ``range_edges`` the same edges as
    range r = c t / 2 − D (scene units, metres); ``angles_deg``, ``view_vectors`` the views;
    ``radiometry``, ``units``: typed fields (as :class:`~meshladar.sinogram.Sinogram`'s);
    ``info``: free-form provenance (standoff, pulse, response, sample rate), read-only, that
    also shows the typed fields (``info["units"]`` reads for one release).

    Parameters
    ----------
    values : (n_views, n_samples) array_like
        Signal per sample; finite, stored as a read-only float64 copy.
    time_edges : (n_samples + 1,) array_like
        Sample edges, two-way time, s; finite and strictly increasing. Keyword-only.
    angles_deg : (n_views,) array_like
        View angles, degrees (as :class:`~meshladar.sinogram.Sinogram`'s); stored as a
        read-only float64 copy, not checked. Keyword-only.
    view_vectors : (n_views, 3) array_like
        View directions; stored as a read-only float64 copy, not checked. Keyword-only.
    standoff : float
        D, m, for :attr:`range_edges` (default 0.0, a ladar at infinity); not checked.
        Keyword-only.
    info : dict
        Free-form provenance (default empty); a ``"radiometry"`` or ``"units"`` key fills
        the field of that name. Keyword-only.
    radiometry : str, optional
        ``"paper"`` or ``"power"``, as the sinogram's; None when unknown. Keyword-only.
    units : str, optional
        The values' units when not the convention's own (``"photoelectrons"``).
        Keyword-only.

    Raises
    ------
    ParameterError
        When ``values`` or ``time_edges`` is not finite, ``values`` is not 2-D,
        ``time_edges`` has not n_samples + 1 strictly increasing entries, ``info`` is not a
        mapping, or ``radiometry`` or ``units`` is neither a string nor None.
    """

    values: np.ndarray
    time_edges: np.ndarray = field(kw_only=True)
    angles_deg: np.ndarray = field(kw_only=True)
    view_vectors: np.ndarray = field(kw_only=True)
    standoff: float = field(default=0.0, kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)
    radiometry: str | None = field(default=None, kw_only=True)
    units: str | None = field(default=None, kw_only=True)

    def __post_init__(self):
        v = finite_array("values", self.values)
        t = finite_array("time_edges", self.time_edges)
        if v.ndim != 2 or t.shape != (v.shape[1] + 1,) or np.any(np.diff(t) <= 0):
            raise ParameterError(f"values must be (n_views, n_samples) and time_edges "
                                 f"n_samples + 1 increasing times; got {v.shape} and "
                                 f"{t.shape}")
        object.__setattr__(self, "values", readonly_copy(v))
        object.__setattr__(self, "time_edges", readonly_copy(t))
        object.__setattr__(self, "angles_deg", readonly_copy(self.angles_deg))
        object.__setattr__(self, "view_vectors", readonly_copy(self.view_vectors))
        split_info(self, self.info, keep_none=True)

    @property
    def sample_interval(self) -> float:
        """Δt, s."""
        return float(self.time_edges[1] - self.time_edges[0])

    @property
    def times(self) -> np.ndarray:
        """(n_samples,) sample centres, s."""
        return 0.5 * (self.time_edges[1:] + self.time_edges[:-1])

    @property
    def range_edges(self) -> np.ndarray:
        """Sample edges as range, c t / 2 − D (m)."""
        return SPEED_OF_LIGHT * self.time_edges / 2.0 - self.standoff

    def total(self) -> np.ndarray:
        """(n_views,) total signal of each view: the sum of its samples.

        Returns
        -------
        (n_views,) numpy.ndarray
            ``values.sum(axis=1)``, in the waveforms' units.
        """
        return self.values.sum(axis=1)

    def scaled(self, factor, units="photoelectrons") -> "Waveforms":
        """The same waveforms times ``factor`` (e.g. photoelectrons per unit of a relative
        power sinogram), in ``units``; photoelectrons are not scaled to photoelectrons
        again (a double count).

        Parameters
        ----------
        factor : float
            Multiplier, finite and > 0 (units per unit of the current values).
        units : str or None
            Units of the scaled values (default ``"photoelectrons"``).

        Returns
        -------
        Waveforms
            A new record: values × ``factor``, the same times and views, ``units`` as
            given, and ``info`` the provenance plus ``scaled_by`` (the factor).

        Raises
        ------
        ParameterError
            When ``factor`` is not a finite number > 0, when the waveforms already count
            photoelectrons and ``units`` is ``"photoelectrons"``, or when ``units`` is
            neither a string nor None.
        """
        f = check_real("factor", factor, low=0.0, low_open=True)
        if self.units == "photoelectrons" and units == "photoelectrons":
            raise ParameterError("these waveforms already count photoelectrons (their sensor "
                                 "counted them): scaling them to photoelectrons again would "
                                 "count twice; scale waveforms of relative power, or give "
                                 "the units the factor converts to")
        return Waveforms(self.values * f, time_edges=self.time_edges,
                         angles_deg=self.angles_deg, view_vectors=self.view_vectors,
                         standoff=self.standoff, info=dict(self.provenance, scaled_by=f),
                         radiometry=self.radiometry, units=units)

    @property
    def provenance(self) -> dict:
        """The free-form part of :attr:`info` (without the typed fields), as a new dict."""
        return {k: v for k, v in self.info.items() if k not in TYPED_INFO_KEYS}

    def realise(self, noise: Noise, n=1, *, seed=None) -> np.ndarray:
        """``n`` noise realisations, (n, n_views, n_samples), in the noise's output units
        (gain × photoelectrons, quantised if asked). Seeded: the same seed gives the same
        bits. The waveforms must count photoelectrons (a sensor with ``pulse_energy`` and
        ``aperture_diameter``, or :meth:`scaled`).

        Parameters
        ----------
        noise : meshladar.noise.Noise
            The receiver's noise.
        n : int
            Number of realisations, ≥ 1 (default 1).
        seed : int, sequence of int or None
            Seed of numpy's default generator (default None: fresh entropy). Keyword-only.

        Returns
        -------
        (n, n_views, n_samples) numpy.ndarray
            float64 draws (:func:`meshladar.noise.draw_noise`, dwell the sample interval).

        Raises
        ------
        ParameterError
            When ``noise`` is not a Noise, ``n`` is not an integer ≥ 1, ``seed`` is
            invalid, the waveforms' ``units`` are not ``"photoelectrons"``, or the draws
            would pass meshladar's allocation cap or mean-count limit.

        Warns
        -----
        MeshladarWarning
            When quantised draws clip at the digitiser's top code.
        """
        if not isinstance(noise, Noise):
            raise ParameterError(f"noise must be a meshladar.noise.Noise; got "
                                 f"{type(noise).__name__}")
        n = check_count("n", n)
        check_seed("seed", seed)
        if self.units != "photoelectrons":
            raise ParameterError(
                f"noise counts photoelectrons; these waveforms are in "
                f"{self.units!r}: simulate with a Sensor that has pulse_energy "
                "and aperture_diameter (the command line's --pulse-energy, --aperture), or "
                "convert with Waveforms.scaled(factor) (receive's --scale)")
        return draw_noise(noise, self.values, self.sample_interval, n, seed)

    def detection_probability(self, noise: Noise, threshold, n=1000, *, seed=None,
                              chunk=100):
        """Monte-Carlo detection statistics of a threshold detector on each view.

        Returns a dict: ``detection`` (n_views,), the fraction of ``n`` noisy pulses in
        which any sample of the view reaches ``threshold`` (output units); ``false_alarm``,
        the fraction of samples that reach it in noise alone (background and dark counts,
        the same gain and quantisation) over as many samples; ``threshold`` and ``n``.
        Seeded; drawn ``chunk`` pulses at a time (bounded memory), at most
        :data:`MAX_DETECTION_DRAWS` samples in all (bounded time).

        Parameters
        ----------
        noise : meshladar.noise.Noise
            The receiver's noise.
        threshold : float
            Detection threshold, output units; finite and > 0.
        n : int
            Number of noisy pulses, ≥ 1 (default 1000); 2 n × ``values.size`` must not pass
            :data:`MAX_DETECTION_DRAWS`.
        seed : int, sequence of int or None
            Seed of numpy's default generator, from which each chunk's seeds are drawn
            (default None: fresh entropy). Keyword-only.
        chunk : int
            Pulses drawn at a time, ≥ 1 (default 100).

        Returns
        -------
        dict
            ``detection`` ((n_views,) numpy.ndarray, in [0, 1]), ``false_alarm`` (float,
            in [0, 1]), ``threshold`` (float) and ``n`` (int).

        Raises
        ------
        ParameterError
            When ``threshold``, ``n``, ``chunk`` or ``seed`` is invalid, the draws would
            pass :data:`MAX_DETECTION_DRAWS`, or :meth:`realise` refuses (``noise`` not a
            Noise, waveforms not in photoelectrons).
        """
        thr = check_real("threshold", threshold, low=0.0, low_open=True)
        n = check_count("n", n)
        draws = 2.0 * n * self.values.size
        if draws > MAX_DETECTION_DRAWS:
            raise ParameterError(f"n: {n} pulses of {self.values.size} samples would draw "
                                 f"{draws:.3g} samples, more than the {MAX_DETECTION_DRAWS:.0e} "
                                 "detection_probability draws; give a smaller n")
        chunk = check_count("chunk", chunk)
        rng = np.random.default_rng(check_seed("seed", seed))
        hits = np.zeros(self.values.shape[0])
        alarms = 0
        quiet = Waveforms(np.zeros_like(self.values), time_edges=self.time_edges,
                          angles_deg=self.angles_deg, view_vectors=self.view_vectors,
                          standoff=self.standoff, info=self.info)
        for start in range(0, n, chunk):
            k = min(chunk, n - start)
            seeds = rng.integers(0, 2**63, 2)
            hits += (self.realise(noise, k, seed=int(seeds[0])) >= thr).any(axis=2).sum(0)
            alarms += int((quiet.realise(noise, k, seed=int(seeds[1])) >= thr).sum())
        return {"detection": hits / n, "false_alarm": alarms / (n * self.values.size),
                "threshold": thr, "n": n}

    def plot(self, *, noise=None, realisations=8, seed=0, views=None):
        """A quick look (:func:`meshladar.viz.waveforms.figure`, through :mod:`meshladar.plotting`): a few views' waveforms,
        with ``noise`` the band of ``realisations`` draws around the expected waveform;
        a matplotlib Figure.

        Parameters
        ----------
        noise : meshladar.noise.Noise, optional
            Draws this noise's realisations (:meth:`realise`) for the band (default None:
            the noiseless waveforms only). Keyword-only.
        realisations : int
            Number of realisations drawn with ``noise`` (default 8). Keyword-only.
        seed : int, sequence of int or None
            Seed of the realisations (default 0). Keyword-only.
        views : sequence of int, optional
            Which views (default up to four, spread over all). Keyword-only.

        Returns
        -------
        matplotlib.figure.Figure
            The views' waveforms.

        Raises
        ------
        ParameterError
            When :meth:`realise` refuses the noise, ``realisations`` or ``seed``.
        ImportError
            When the ``viz`` extra is not installed.
        """
        draws = None if noise is None else self.realise(noise, realisations, seed=seed)
        return plotting.plot(self, realisations=draws, noise=noise, views=views)

    def _summary(self):
        return (("n_views", self.values.shape[0]), ("n_samples", self.values.shape[1]),
                ("time", f"{self.time_edges[0] * 1e9:.7g} to {self.time_edges[-1] * 1e9:.7g}"
                         " ns (two-way)"),
                ("units", self.units), ("radiometry", self.radiometry))

    def __repr__(self) -> str:
        return text("Waveforms", *self._summary())

    def _repr_html_(self) -> str:
        return table("Waveforms", *self._summary())


def _window(sino, t_edges, dt, m, shapes):
    """The pulse's and response's kernels on ``dt`` cells, their lead in cells, and the
    digitiser's window (first, last sample), each size checked before it is made."""
    for name, shape in zip(("pulse", "response"), shapes):
        if shape is not None:        # its kernel's cells, counted before any is made
            check_size("sample_rate", (shape.support[1] - shape.support[0]) / dt + 2, 8 * 3,
                       f"a {name} {shape.support[1] - shape.support[0]:.3g} s long on "
                       f"{dt:.3g} s cells", f"give a lower sample_rate or a shorter {name}")
    (kp, p0), (kr, r0) = (_kernel(shape, dt) for shape in shapes)
    # whole samples from the first bin's start (less the kernels' lead) to the last bin's
    # end (plus their tails)
    first = math.floor((t_edges[0] / dt + p0 + r0) / m)
    last = math.ceil((t_edges[-1] / dt + p0 + r0 + kp.size + kr.size) / m)
    # the FFT convolution's peak (measured: tests/values/test_receive_memory.py)
    check_size("sample_rate", float((last - first) * m + kp.size + kr.size)
               * (sino.n_views + 1), RECEIVE_PEAK_BYTES,
               f"{(last - first) * m} fine cells per view ({last - first} samples) "
               f"convolved with a {kp.size + kr.size}-cell kernel",
               "give a lower sample_rate, a shorter pulse or fewer bins")
    return kp, kr, p0 + r0, (first, last)


def receive(sino: Sinogram, *, sample_rate, pulse=None, response=None, standoff=None,
            oversample=8) -> Waveforms:
    """The waveforms a digitiser records from a sinogram's range bins.

    Parameters
    ----------
    sino : Sinogram
        Range profiles, best of received power (``radiometry="power"``); in photoelectrons
        when simulated with a :class:`~meshladar.sensor.Sensor` that counts them.
    sample_rate : float
        Digitiser rate, Hz (samples per second), in :data:`SAMPLE_RATE_RANGE` (1 Hz to
        10¹⁸ Hz).
    pulse : GaussianPulse or SampledPulse, optional
        The transmitted pulse's power against time (default: none, a Dirac pulse).
    response : GaussianPulse or SampledPulse, optional
        The receiver's impulse response (default: none, ideal).
    standoff : float, optional
        D (m) for the time origin t = 2(r + D)/c; default the sinogram's sensor's, else 0.
    oversample : int
        Fine cells per digitiser sample for the convolutions (default 8, at most
        :data:`MAX_OVERSAMPLE`).

    Returns
    -------
    Waveforms
        Each view's samples; they sum to its bins (module docstring).

    Raises
    ------
    ParameterError
        When ``sino`` is not a Sinogram or holds a negative value, ``sample_rate``,
        ``oversample`` or ``standoff`` (at most 1e9 m) is out of range, ``pulse`` or
        ``response`` is of the wrong type, or the convolution would need more than
        meshladar's allocation cap.
    """
    check_sinogram("sino", sino)
    if np.any(sino.values < 0):
        raise ParameterError(f"sino must hold received power or counts (>= 0); its smallest "
                             f"value is {float(sino.values.min()):.4g} (log or clipped "
                             "input, or a difference, is not a power)")
    fs = check_real("sample_rate", sample_rate, low=SAMPLE_RATE_RANGE[0],
                    high=SAMPLE_RATE_RANGE[1])
    pulse = _check_shape("pulse", pulse)
    response = _check_shape("response", response)
    m = check_count("oversample", oversample, high=MAX_OVERSAMPLE)
    name = "standoff"
    if standoff is None:        # a file's record is named as such, not as the argument
        name, standoff = ("the sinogram's info['sensor']['standoff_m']",
                          (sino.info.get("sensor") or {}).get("standoff_m") or 0.0)
    D = check_real(name, standoff, low=0.0, high=SENSOR_LIMITS["standoff"])
    t_edges = 2.0 * (sino.bin_edges + D) / SPEED_OF_LIGHT
    dt = 1.0 / (fs * m)
    kp, kr, shift, (first, last) = _window(sino, t_edges, dt, m, (pulse, response))
    n_fine = (last - first) * m
    fine_edges = (first * m + np.arange(n_fine + 1)) * dt
    # each bin spread uniformly over its time interval: a piecewise-linear CDF per view
    cum = np.concatenate([np.zeros((sino.n_views, 1)), np.cumsum(sino.values, axis=1)], 1)
    # the kernels shift the signal by (p0 + r0) cells: deposit at the shifted edges
    shifted = fine_edges - shift * dt
    fine = np.empty((sino.n_views, n_fine))
    for i in range(sino.n_views):
        fine[i] = np.diff(np.interp(shifted, t_edges, cum[i]))
    kernel = np.convolve(kp, kr)
    from scipy.signal import convolve

    # (the window's tail holds the whole kernel, so nothing is cut; an FFT's rounding can
    # leave −1e-17 where there is no signal: clipped)
    out = np.maximum(convolve(fine, kernel[None, :], mode="full")[:, :n_fine], 0.0)
    samples = out.reshape(sino.n_views, last - first, m).sum(axis=2)
    info = {"standoff_m": D, "sample_rate_hz": fs, "oversample": m,
            "pulse": None if pulse is None else pulse.describe(),
            "response": None if response is None else response.describe(),
            "time_origin": "two-way time t = 2 (r + standoff) / c, s (less 2 aim.w / c with "
                           "a sensor aimed off the origin)",
            "source_model": sino.model, "sensor": sino.info.get("sensor"),
            "source_info": {k: v for k, v in sino.info.items() if k != "sensor"}}
    return Waveforms(samples, time_edges=(first + np.arange(last - first + 1)) / fs,
                     angles_deg=sino.angles_deg, view_vectors=sino.view_vectors,
                     standoff=D, info=info, radiometry=sino.radiometry, units=sino.units)
