"""The scanner's transmitter, receiver and detector: :class:`ScanSensor` and
:class:`Detector`.

Linear-mode detection: a return is a local maximum of the (noisy) waveform at or above the
threshold, in photoelectrons per sample, farther than the echo's FWHM from every stronger
one (weaker maxima within it are noise on the same echo). The threshold is ``threshold`` when given, else
the Poisson one for the receiver's background and dark counts b per sample: the smallest
count n with P(N ≥ n | b) ≤ ``false_alarm`` (so a noise-only sample crosses it with
probability at most ``false_alarm``), and at least one photoelectron; with ``cfar=True``
b is each record's own background, estimated from the record (a background the sensor
does not know: sunlight on a bright field). Each return's time
comes from a Gaussian through its three samples (log-parabola interpolation: exact for a
sampled Gaussian), its width and intensity (photoelectrons under it) from the same fit.
Peaks closer than four pulse widths (σ) are refitted together as a sum of Gaussians
(their Gaussian decomposition); echoes closer than the pulse's resolution merge into one
maximum and give one return.
"""

from __future__ import annotations

import math
import functools
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._pulses import GaussianPulse, SampledPulse
from .._validate import check_choice, check_count, check_real
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..noise import Noise
from ..sensor import LIMITS, MIN_WAVELENGTH
from ._sampling import echo_shape, echo_support
from .footprint import ScanBeam
from .geiger import GeigerMode

__all__ = ["ScanSensor", "Detector", "MAX_SAMPLES", "ECHO_MODELS", "FWHM_PER_SIGMA",
           "MIN_SAMPLES_PER_ECHO", "FEW_SAMPLES_PER_ECHO"]

#: A Gaussian's full width at half maximum over its σ, 2 sqrt(2 ln 2).
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))

#: How a pulse's echoes become returns (:class:`ScanSensor`'s ``echoes``).
ECHO_MODELS = ("waveform", "discrete")

#: The longest record a pulse's waveform may hold (samples).
MAX_SAMPLES = 1 << 16

#: The fewest samples across a linear receiver's echo (its FWHM) that the detector takes,
#: and the fewest it takes without a warning. Measured on a plate over sub-sample offsets:
#: ranges within 0.14 % of c τ / 2 and photoelectrons within 0.2 % from 2 samples; 1.3 %
#: and 2.2 % from 1 to 2; 46 % and ×1.5 below 1 (ranges on the sample grid).
MIN_SAMPLES_PER_ECHO = 1.0
FEW_SAMPLES_PER_ECHO = 2.0
#: The relative rounding a rate given as its 3 significant figures carries.
_ROUNDING = 5e-3


def _up(rate):
    """``rate`` rounded up to 3 significant figures (a rate advised is never short)."""
    step = 10.0 ** (math.floor(math.log10(rate)) - 2)
    return math.ceil(rate / step * (1.0 - 1e-12)) * step


def _moments(shape):
    """(mean, variance) of a pulse shape's time, s."""
    if isinstance(shape, GaussianPulse):
        return 0.0, (shape.fwhm / FWHM_PER_SIGMA) ** 2
    k = np.arange(shape.samples.size)
    t = shape.start + (k + 0.5) * shape.interval
    mean = float(np.sum(shape.samples * t))
    return mean, float(np.sum(shape.samples * (t - mean) ** 2)) + shape.interval ** 2 / 12.0


@dataclass(frozen=True)
class Detector:
    """Linear-mode detection (module docstring).

    Parameters
    ----------
    threshold : float, optional
        Photoelectrons per sample (> 0); default the Poisson threshold for ``false_alarm``.
    false_alarm : float
        The largest probability that a noise-only sample crosses the threshold, in
        (0, 0.5] (default 1e-6).
    max_returns : int
        The most returns kept per pulse (the strongest), 1 to 15 (LAS's limit; default 5).
    decompose : bool
        Refit overlapping peaks as a sum of Gaussians (default True).
    cfar : bool
        Constant false-alarm rate: the Poisson threshold of each record's own background,
        estimated from it (its samples beyond two echo widths of its largest, their sum
        plus one over their number: cell averaging kept off zero), not the sensor's
        stated rates (default False). Linear mode only.
    """

    threshold: float | None = None
    false_alarm: float = 1e-6
    max_returns: int = 5
    decompose: bool = True
    cfar: bool = False

    def __post_init__(self):
        if self.threshold is not None:
            object.__setattr__(self, "threshold", check_real(
                "threshold", self.threshold, low=0.0, low_open=True, high=1e15))
        object.__setattr__(self, "false_alarm", check_real(
            "false_alarm", self.false_alarm, low=0.0, low_open=True, high=0.5))
        object.__setattr__(self, "max_returns", check_count("max_returns", self.max_returns,
                                                            high=15))
        for name in ("decompose", "cfar"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"{name} must be True or False; got "
                                     f"{getattr(self, name)!r}")
        if self.cfar and self.threshold is not None:
            raise ParameterError("cfar sets the threshold from each record's background; "
                                 f"give cfar=True or threshold={self.threshold:g}, not both")

    def level(self, background):
        """The threshold for a background (module docstring).

        Parameters
        ----------
        background : float or numpy.ndarray
            Mean background counts per sample.

        Returns
        -------
        float or numpy.ndarray
            Photoelectrons per sample (``threshold`` when given), the shape of
            ``background``.
        """
        if self.threshold is not None:
            return self.threshold
        if np.ndim(background) == 0:                           # a sensor's: every chunk's
            return _poisson_level(self.false_alarm, float(background))
        from scipy.stats import poisson

        return np.maximum(1.0, poisson.isf(self.false_alarm, background) + 1)

    def describe(self) -> dict:
        """The parameters (for result files).

        Returns
        -------
        dict
            ``threshold_pe``, ``false_alarm``, ``max_returns``, ``decompose``, ``cfar``.
        """
        return {"threshold_pe": self.threshold, "false_alarm": self.false_alarm,
                "max_returns": self.max_returns, "decompose": self.decompose,
                "cfar": self.cfar}


@dataclass(frozen=True)
class ScanSensor:
    """A scanning ladar's transmitter and receiver (monostatic; :mod:`.cast`'s link budget).

    Parameters
    ----------
    pulse_energy : float
        Energy per pulse, J (a flash array's whole frame), in (0, 1e9].
    aperture_diameter : float
        Receiver aperture diameter, m, in (0, 1e3].
    sample_rate : float
        The digitiser's samples per second, in (0, 1e15].
    pulse : GaussianPulse or SampledPulse
        The transmitted pulse (default a Gaussian of 5 ns FWHM).
    response : GaussianPulse or SampledPulse, optional
        The receiver's impulse response. Two Gaussians combine exactly (FWHMs in
        quadrature, erf integrals); any other pair is convolved on a fine table. A
        return's time is its echo's centroid less the combined shape's mean
        (:attr:`delay`), so a shape that does not start at t = 0 ranges true.
    beam : ScanBeam
        The beam's divergence and profile (default one ray per pulse). A flash array's
        pixels are lit uniformly over their IFOV and take only the beam's ``tol`` (their
        sub-rays, :mod:`.footprint`): a flash scan refuses a beam whose divergence,
        profile or ``sub_rays`` is set, and records its pixels' sampling as the beam.
    noise : meshladar.noise.Noise, optional
        The receiver's noise (shot noise of signal, background and dark counts, speckle,
        APD gain); None: the expected waveform, no noise.
    detector : Detector
        How returns are found (default :class:`Detector`'s).
    samples : int, optional
        The record length per pulse (samples), at least :attr:`echo_samples`; default each
        chunk's spread of echoes plus the pulse's support on either side. A record starts
        at its pulse's first echo less the support: an echo that ends past a fixed
        record's end is cut, a return whose centroid window it cuts is dropped, and the
        scan warns
        (:class:`~meshladar.errors.RecordLengthWarning`), naming the length that holds
        them.
    echoes : str
        ``"waveform"`` (default): each pulse's record synthesised, with its noise, and
        searched for returns. ``"discrete"``: no record; a pulse's lit sub-rays grouped
        in time (a new return where arrivals are more than the echo's FWHM apart), each
        group at or above the detector's threshold (1 photoelectron by default) a return
        at its photoelectron-weighted range, expected values without noise (the fast,
        ideal point cloud; ``noise``, ``geiger``, ``samples`` and CFAR do not apply and are
        refused).
    geiger : GeigerMode, optional
        Geiger-mode pixels instead of a linear receiver (:mod:`.geiger`): each pattern pulse
        is ``shots`` shots histogrammed and Coates-corrected; the noise's background and
        dark rates are its b (speckle, gain and quantisation do not apply and are refused).
    wavelength, optics_transmission, quantum_efficiency, extinction : float
        As :class:`meshladar.sensor.Sensor`'s (m; (0, 1]; (0, 1]; 1/m).
    """

    pulse_energy: float
    aperture_diameter: float
    sample_rate: float
    pulse: GaussianPulse | SampledPulse = field(default_factory=lambda: GaussianPulse(5e-9))
    response: GaussianPulse | SampledPulse | None = None
    beam: ScanBeam = field(default_factory=ScanBeam)
    noise: Noise | None = None
    detector: Detector = field(default_factory=Detector)
    samples: int | None = None
    echoes: str = "waveform"
    geiger: GeigerMode | None = None
    wavelength: float = 1.064e-6
    optics_transmission: float = 1.0
    quantum_efficiency: float = 1.0
    extinction: float = 0.0

    def __post_init__(self):
        for name, high in (("pulse_energy", LIMITS["pulse_energy"]),
                           ("aperture_diameter", LIMITS["aperture_diameter"]),
                           ("sample_rate", 1e15)):
            object.__setattr__(self, name, check_real(name, getattr(self, name), low=0.0,
                                                      low_open=True, high=high))
        for name, kind in (("pulse", (GaussianPulse, SampledPulse)),
                           ("response", (GaussianPulse, SampledPulse, type(None))),
                           ("beam", ScanBeam), ("noise", (Noise, type(None))),
                           ("detector", Detector), ("geiger", (GeigerMode, type(None)))):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError(f"{name} must be a {getattr(kind, '__name__', kind)}; "
                                     f"got {type(getattr(self, name)).__name__}")
        if self.samples is not None:
            object.__setattr__(self, "samples", check_count("samples", self.samples,
                                                            low=3, high=MAX_SAMPLES))
        if self.geiger is not None and self.noise is not None and (
                self.noise.speckle_cells is not None or self.noise.gain != 1.0
                or self.noise.excess_noise_factor != 1.0 or self.noise.bits is not None):
            raise ParameterError("geiger: Geiger-mode pixels count avalanches; the noise's "
                                 "speckle_cells, gain, excess_noise_factor and bits do not "
                                 "apply (give only background_rate and dark_rate)")
        check_choice("echoes", self.echoes, ECHO_MODELS)
        if self.echoes == "discrete":
            given = [n for n in ("noise", "geiger", "samples") if getattr(self, n) is not None]
            if given or self.detector.cfar:
                raise ParameterError(f"echoes='discrete' has no records: "
                                     f"{(given or ['detector.cfar'])[0]} does not apply "
                                     "(use echoes='waveform')")
        if self.echoes == "waveform":
            self._check_echo_sampling()
        if self.samples is not None and self.samples < self.echo_samples:
            raise ParameterError(
                f"samples: a record of {self.samples} samples cannot hold one echo (its "
                f"support at {self.sample_rate:.3g} samples/s takes {self.echo_samples}); "
                f"give {self.echo_samples} or more, or leave samples unset (each chunk's "
                "spread of echoes)")
        if self.geiger is not None and self.detector.cfar:
            raise ParameterError("detector: cfar applies to a linear receiver's records; "
                                 "Geiger-mode thresholds follow each sample's armed shots")
        object.__setattr__(self, "wavelength", check_real(
            "wavelength", self.wavelength, low=MIN_WAVELENGTH, high=LIMITS["wavelength"]))
        for name in ("optics_transmission", "quantum_efficiency"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), low=0.0,
                                                      low_open=True, high=1.0))
        object.__setattr__(self, "extinction", check_real("extinction", self.extinction,
                                                          low=0.0, high=1.0))

    def _check_echo_sampling(self):
        """Refuse an echo narrower than :data:`MIN_SAMPLES_PER_ECHO` samples (its
        :attr:`fwhm`: 2.355 σ, a Gaussian's FWHM; the detector's matched filter and peak fit
        are Gaussians of its σ), warn below :data:`FEW_SAMPLES_PER_ECHO` (to rounding),
        and refuse one whose support a record cannot hold (:data:`MAX_SAMPLES`); a
        Geiger-mode array's histogram bins too (its returns are read from the corrected
        histogram by the same detector: at half a bin per FWHM a return read 1.48 of
        its photoelectrons)."""
        if self.echo_samples > MAX_SAMPLES:
            raise ParameterError(f"the echo (the pulse and the response) takes "
                                 f"{self.echo_samples} samples at sample_rate="
                                 f"{self.sample_rate:g}, more than a record's {MAX_SAMPLES}: "
                                 "give a lower sample_rate or a shorter pulse")
        across = self.fwhm * self.sample_rate
        need = _up(FEW_SAMPLES_PER_ECHO / self.fwhm)
        what = (f"the echo (the pulse and the response: 2.355 sigma = {self.fwhm:.3g} s, a "
                f"Gaussian's FWHM) spans {across:.3g} samples at "
                f"sample_rate={self.sample_rate:g}")
        if across < MIN_SAMPLES_PER_ECHO:
            raise ParameterError(f"{what}; the detector (a linear receiver's, or a "
                                 f"Geiger-mode array's on its histogram) needs "
                                 f"{MIN_SAMPLES_PER_ECHO:g} or more (ranges fall on the "
                                 f"sample grid): give sample_rate >= {need:.3g} or a wider "
                                 "pulse")
        if across < FEW_SAMPLES_PER_ECHO * (1.0 - _ROUNDING):
            warnings.warn(f"{what}: ranges may be off by ~1 % of c tau / 2 and "
                          f"photoelectrons by ~2 % (a Gaussian echo's, within 0.2 % from "
                          f"{FEW_SAMPLES_PER_ECHO:g} samples): give sample_rate >= "
                          f"{need:.3g} or a wider pulse", MeshladarWarning,
                          stacklevel=user_stacklevel())

    @property
    def dt(self) -> float:
        """The sample interval, s."""
        return 1.0 / self.sample_rate

    @property
    def sigma(self) -> float:
        """The received echo's standard deviation (RMS width) in time, s: the pulse's and
        the response's in quadrature."""
        shapes = [self.pulse] + ([self.response] if self.response is not None else [])
        return sum(_moments(x)[1] for x in shapes) ** 0.5

    @functools.cached_property
    def echo_samples(self) -> int:
        """The samples one echo's record takes: its support (:data:`SUPPORT
        <meshladar.scan.echoes.SUPPORT>` σ either side of a Gaussian echo, the echo shape's
        extent for a sampled pulse or response), and two (a record starts on a sample);
        the fewest ``samples`` may be."""
        before, after = echo_support(self.sigma, echo_shape(self.pulse, self.response,
                                                            self.dt))
        return math.ceil((before + after) / self.dt) + 2

    @property
    def fwhm(self) -> float:
        """The received echo's full width at half maximum, s (:attr:`sigma` × 2.3548)."""
        return FWHM_PER_SIGMA * self.sigma

    @property
    def delay(self) -> float:
        """The echo shape's mean time after the surface's two-way time, s (0 for
        Gaussians)."""
        shapes = [self.pulse] + ([self.response] if self.response is not None else [])
        return sum(_moments(x)[0] for x in shapes)

    def background(self) -> float:
        """Mean background and dark counts per sample.

        Returns
        -------
        float
            (background_rate + dark_rate) Δt, 0 without noise.
        """
        if self.noise is None:
            return 0.0
        return (self.noise.background_rate + self.noise.dark_rate) * self.dt

    def describe(self) -> dict:
        """Every parameter with its unit in its name (for result files).

        Returns
        -------
        dict
            The energy, aperture, sample rate, pulse, response, beam, noise, detector,
            record length, Geiger mode, wavelength, optics, quantum efficiency and
            extinction.
        """
        return {"pulse_energy_J": self.pulse_energy,
                "aperture_diameter_m": self.aperture_diameter,
                "sample_rate_hz": self.sample_rate, "pulse": self.pulse.describe(),
                "response": self.response.describe() if self.response else None,
                "beam": self.beam.describe(),
                "noise": None if self.noise is None else {
                    k: getattr(self.noise, k) for k in (
                        "speckle_cells", "background_rate", "dark_rate",
                        "excess_noise_factor", "gain", "bits", "full_scale")},
                "detector": self.detector.describe(), "samples": self.samples,
                "echoes": self.echoes,
                "geiger": self.geiger.describe() if self.geiger else None,
                "wavelength_m": self.wavelength,
                "optics_transmission": self.optics_transmission,
                "quantum_efficiency": self.quantum_efficiency,
                "extinction_per_m": self.extinction}


@functools.lru_cache(maxsize=64)
def _poisson_level(false_alarm, background):
    """:meth:`Detector.level` of one background, kept: scipy's Poisson quantile takes
    ~0.3 ms, holding the GIL, in every chunk of a scan."""
    from scipy.stats import poisson

    return max(1.0, float(poisson.isf(false_alarm, background) + 1))  # P(N ≥ n) ≤ pfa
