"""The sensor: what a ladar's receiver records (the sensor chain of the guide's Concepts page).

Radiometry conventions (``radiometry=`` on every forward model and on :func:`weigh`):

``"paper"``
    The paper's Eq. 8: each bin is ∫ F(θ) cos θ dA over the visible surface whose range lies
    in it (with a beam, times the beam's relative irradiance at each point). This is what
    the paper's figures use; it is not the power a receiver collects.
``"power"``
    Received power: the reflected radiance F E cos θ_i seen over the element's projected
    area toward the receiver, ∫ F cos θ_i cos θ_r dA (monostatic ∫ F cos²θ dA), with the
    receiver's (D/R)² at a finite standoff D. One cos θ more than Eq. 8: a Lambertian
    sphere's profile is ∝ (1 − r/R)², not ∝ (1 − r/R).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_choice, check_real, finite_array
from .errors import ParameterError

__all__ = ["RADIOMETRIES", "FloodBeam", "GaussianBeam", "Sensor", "SPEED_OF_LIGHT", "PLANCK",
           "MIN_WAIST"]

#: Speed of light in vacuum, m/s (exact, SI).
SPEED_OF_LIGHT = 299_792_458.0
#: Planck's constant, J·s (exact, SI).
PLANCK = 6.626_070_15e-34

#: The radiometry conventions every forward model takes (module docstring).
RADIOMETRIES = ("paper", "power")


def check_radiometry(radiometry) -> bool:
    """True for received power, False for the paper's Eq. 8; a ParameterError naming the
    choices otherwise."""
    return check_choice("radiometry", radiometry, RADIOMETRIES) == "power"


#: The largest magnitudes the sensor's computation stays finite and accurate with (its
#: ranges, link budget and Poisson draws): a standoff to 1e9 m (ranges then resolved to
#: 1e9 · 2⁻⁵² ≈ 0.2 µm), pulse energies to 1e9 J, apertures to 1e3 m, wavelengths from
#: 1e-9 m to 1 m. Beyond them a parameter is refused at construction, naming its range.
LIMITS = {"standoff": 1e9, "pulse_energy": 1e9, "aperture_diameter": 1e3, "wavelength": 1.0,
          "radius": 1e9, "waist": 1e9}
#: The shortest wavelength taken (m).
MIN_WAVELENGTH = 1e-9
#: The narrowest Gaussian waist taken (m): a picometre, far below any optics, and its
#: square (the spot's 1/e² radius squared divides the irradiance's exponent) stays normal.
MIN_WAIST = 1e-12


def _optional_positive(name, value):
    return None if value is None else check_real(name, value, low=0.0, low_open=True,
                                                 high=LIMITS.get(name))


@dataclass(frozen=True)
class FloodBeam:
    """A uniform flood: the same radiant intensity in every direction of its cone (at a
    finite standoff the irradiance on a surface facing the sensor falls as (D/R)²), or the
    same irradiance everywhere (sensor at infinity): today's default, the paper's.

    Parameters
    ----------
    radius : float, optional
        Radius (m, scene units) of the lit disk on the plane through the aim point normal to
        the view: a top-hat of that radius (a cone of half-angle atan(radius/D) at standoff
        D). None (default): unbounded. Needed for photoelectrons: the pulse's energy is
        spread over π radius².

    Raises
    ------
    ParameterError
        When ``radius`` is given and not in (0, 1e9] m.
    """

    radius: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "radius", _optional_positive("radius", self.radius))

    def reference_fluence(self, energy, standoff):
        """J/m² at the aim point for a pulse of ``energy`` J.

        Parameters
        ----------
        energy : float
            Pulse energy E, J.
        standoff : float or None
            The sensor's standoff D, m; not used (the lit disk's radius is given at the aim
            point).

        Returns
        -------
        float
            E / (π radius²), J/m².

        Raises
        ------
        ParameterError
            When the flood is unbounded (``radius`` None).
        """
        if self.radius is None:
            raise ParameterError("photoelectrons need the flood's extent: give "
                                 "FloodBeam(radius=...) (m at the aim point), or a "
                                 "GaussianBeam")
        return energy / (math.pi * self.radius ** 2)

    def relative(self, rho, z, standoff):
        """Irradiance on a surface facing the sensor, relative to the aim point's, at
        distance ``rho`` from the beam's axis and ``z`` along it (arrays).

        Parameters
        ----------
        rho : numpy.ndarray
            Distance from the beam's axis, m.
        z : numpy.ndarray or None
            Distance along the axis from the sensor, m (broadcast with ``rho``); not used
            (None from the tracer) with the sensor at infinity.
        standoff : float or None
            The sensor's standoff D, m; None for a sensor at infinity.

        Returns
        -------
        numpy.ndarray
            float64, the shape of ``rho`` (and ``z``). At infinity: 1 where
            ``rho`` ≤ ``radius`` (everywhere when unbounded), else 0. At standoff D:
            D² / (ρ² + z²), 0 outside the cone ρ/z > radius/D when bounded.
        """
        if standoff is None:
            inside = np.ones_like(rho, dtype=bool) if self.radius is None else \
                rho <= self.radius
            return inside.astype(np.float64)
        r2 = rho * rho + z * z
        out = standoff * standoff / r2
        if self.radius is not None:
            out = np.where(rho * standoff <= self.radius * z, out, 0.0)
        return out

    def describe(self):
        """The parameters, with units in their names (for result files).

        Returns
        -------
        dict
            ``{"kind": "flood", "radius_m": radius}``.
        """
        return {"kind": "flood", "radius_m": self.radius}


@dataclass(frozen=True)
class GaussianBeam:
    """A Gaussian spot: irradiance ∝ exp(−2ρ²/w(z)²) at distance ρ from the beam's axis,
    with 1/e² radius w(z) = sqrt(waist² + (divergence·z)²) at distance z from the sensor.

    Parameters
    ----------
    waist : float
        1/e² intensity radius at the sensor (m, scene units); with the sensor at infinity,
        the radius at the target (a collimated beam).
    divergence : float
        Far-field 1/e² half-angle (rad, ≥ 0; 0 for a collimated beam). Needs a finite
        standoff.
    offset : (2,) float
        Pointing offset of the beam's axis at the aim point, along the view's transverse
        axes (u, v) (m): u = z × w normalised (w the view vector), v = w × u.

    Raises
    ------
    ParameterError
        When ``waist`` is not in [1e-12, 1e9] m (:data:`MIN_WAIST`), ``divergence`` not
        in [0, 1] rad, or
        ``offset`` not two finite numbers.
    """

    waist: float
    divergence: float = 0.0
    offset: tuple = (0.0, 0.0)

    def __post_init__(self):
        object.__setattr__(self, "waist", check_real("waist", self.waist, low=MIN_WAIST,
                                                     high=LIMITS["waist"]))
        object.__setattr__(self, "divergence", check_real("divergence", self.divergence,
                                                          low=0.0, high=1.0))
        off = finite_array("offset", self.offset)
        if off.shape != (2,):
            raise ParameterError(f"offset must be two numbers (along u, v); got shape "
                                 f"{off.shape}")
        object.__setattr__(self, "offset", (float(off[0]), float(off[1])))

    def radius(self, z):
        """1/e² radius at distance z from the sensor (m).

        Parameters
        ----------
        z : float or array_like
            Distance from the sensor, m.

        Returns
        -------
        numpy.ndarray
            w(z) = sqrt(waist² + (divergence·z)²), m, the shape of ``z``.
        """
        return np.sqrt(self.waist ** 2 + (self.divergence * np.asarray(z, np.float64)) ** 2)

    def reference_fluence(self, energy, standoff):
        """Peak J/m² on the axis at the aim point's distance: 2E/(π w²).

        Parameters
        ----------
        energy : float
            Pulse energy E, J.
        standoff : float or None
            The sensor's standoff D, m: w = w(D); None (at infinity): w = ``waist``.

        Returns
        -------
        float
            2E / (π w²), J/m².
        """
        w = self.waist if standoff is None else float(self.radius(standoff))
        return 2.0 * energy / (math.pi * w * w)

    def relative(self, rho, z, standoff):
        """Irradiance relative to the axis at the aim point's distance.

        Parameters
        ----------
        rho : numpy.ndarray
            Distance from the beam's axis, m.
        z : numpy.ndarray or None
            Distance along the axis from the sensor, m (broadcast with ``rho``); not used
            (None from the tracer) with the sensor at infinity.
        standoff : float or None
            The sensor's standoff D, m; None for a sensor at infinity.

        Returns
        -------
        numpy.ndarray
            At infinity exp(−2ρ²/waist²); at standoff D (w(D)/w(z))² exp(−2ρ²/w(z)²).
            ``offset`` is not applied here: ``rho`` is measured from the offset axis.
        """
        if standoff is None:
            return np.exp(-2.0 * rho * rho / self.waist ** 2)
        wz = self.radius(z)
        w0 = float(self.radius(standoff))
        return (w0 / wz) ** 2 * np.exp(-2.0 * rho * rho / (wz * wz))

    def describe(self):
        """The parameters, with units in their names (for result files).

        Returns
        -------
        dict
            ``kind`` ("gaussian"), ``waist_m``, ``divergence_rad`` and ``offset_m`` (a
            list of two floats).
        """
        return {"kind": "gaussian", "waist_m": self.waist, "divergence_rad": self.divergence,
                "offset_m": list(self.offset)}


#: The sensor's options that act only on photoelectron counts, with their defaults.
PHOTON_ONLY = {"optics_transmission": 1.0, "quantum_efficiency": 1.0, "wavelength": 1.064e-6}


@dataclass(frozen=True)
class Sensor:
    """Where the ladar is and what it sends and collects (mesh model; ``sensor=``).

    Parameters
    ----------
    standoff : float, optional
        Distance D (m, scene units, at most 1e9: :data:`LIMITS`, as for ``pulse_energy``
        ≤ 1e9 J, ``aperture_diameter`` ≤ 1e3 m and ``wavelength`` in [1e-9, 1] m, the
        ranges in which the computation stays finite) from the sensor to the aim point.
        None (default): at infinity, parallel rays (today's orthographic ladar). Finite:
        rays fan out from the sensor at ``aim + D w``; ranges are true distances R from it, reported as
        r = R − D − aim·w (R − D when aiming at the origin): the sensor's distance from the
        plane through the origin is D + aim·w, so r tends to the ladar at infinity's −p·w
        and its bins still fit; the two-way time is 2R/c = 2(r + D + aim·w)/c. Each ray
        carries its cross-section at the hit, and received power the receiver's (D/R)².
    aim : (3,) float
        The point the boresight passes through (default the origin, the axis the views turn
        about).
    beam : FloodBeam or GaussianBeam
        The transmitted beam's pattern (default an unbounded flood).
    extinction : float
        Atmospheric extinction coefficient σ (1/m, ≥ 0): received power is multiplied by the
        two-way transmission exp(−2σR). Received power only: with ``radiometry="paper"``
        (Eq. 8, no receiver) a non-zero extinction is an error.
    pulse_energy : float, optional
        Transmitted energy per pulse (J). With ``aperture_diameter`` and a finite standoff,
        received power is counted in photoelectrons per bin.
    aperture_diameter : float, optional
        Receiver aperture diameter (m).
    optics_transmission, quantum_efficiency : float in (0, 1]
        Receive optics' transmission and the detector's quantum efficiency (default 1).
    wavelength : float
        m (default 1.064e-6, Nd:YAG): the photon energy hc/λ.

    Raises
    ------
    ParameterError
        When a parameter is outside its range above (``standoff``, ``pulse_energy`` and
        ``aperture_diameter`` must be > 0), ``aim`` is not three finite numbers, ``beam``
        is not a FloodBeam or GaussianBeam, a beam's divergence or a non-zero extinction
        is given without a standoff, only one of ``pulse_energy`` and
        ``aperture_diameter`` is given, they are given without a standoff, or
        ``optics_transmission``, ``quantum_efficiency`` or ``wavelength`` differs from its
        default without them.
    """

    standoff: float | None = None
    aim: tuple = (0.0, 0.0, 0.0)
    beam: FloodBeam | GaussianBeam = field(default_factory=FloodBeam)
    extinction: float = 0.0
    pulse_energy: float | None = None
    aperture_diameter: float | None = None
    optics_transmission: float = 1.0
    quantum_efficiency: float = 1.0
    wavelength: float = 1.064e-6

    def __post_init__(self):
        object.__setattr__(self, "standoff", _optional_positive("standoff", self.standoff))
        aim = finite_array("aim", self.aim)
        if aim.shape != (3,):
            raise ParameterError(f"aim must be a point (x, y, z); got shape {aim.shape}")
        object.__setattr__(self, "aim", tuple(float(x) for x in aim))
        if not isinstance(self.beam, (FloodBeam, GaussianBeam)):
            raise ParameterError(f"beam must be a FloodBeam or a GaussianBeam; got "
                                 f"{type(self.beam).__name__}")
        if (self.standoff is None and isinstance(self.beam, GaussianBeam)
                and self.beam.divergence > 0):
            raise ParameterError(f"a beam's divergence ({self.beam.divergence:g} rad) needs a "
                                 "finite standoff; with the sensor at infinity give the "
                                 "spot's waist at the target and divergence=0")
        object.__setattr__(self, "extinction", check_real("extinction", self.extinction,
                                                          low=0.0))
        if self.extinction > 0 and self.standoff is None:
            raise ParameterError(f"extinction ({self.extinction:g} per m) needs a finite "
                                 "standoff: the path through the air is the range from it")
        for name in ("pulse_energy", "aperture_diameter"):
            object.__setattr__(self, name, _optional_positive(name, getattr(self, name)))
        for name in ("optics_transmission", "quantum_efficiency"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), low=0.0,
                                                      high=1.0, low_open=True))
        object.__setattr__(self, "wavelength", check_real("wavelength", self.wavelength,
                                                          low=MIN_WAVELENGTH,
                                                          high=LIMITS["wavelength"]))
        self._check_photon_options()

    def _check_photon_options(self):
        """Refuse photon-counting options that the others make meaningless (issue 29: they
        were accepted and silently ignored): energy and aperture only together, at a
        finite standoff; the optics, quantum efficiency and wavelength only with them."""
        given = [n for n in ("pulse_energy", "aperture_diameter") if getattr(self, n) is not None]
        if len(given) == 1:
            other = ({"pulse_energy", "aperture_diameter"} - set(given)).pop()
            raise ParameterError(f"{given[0]} counts photoelectrons only together with {other} "
                                 f"(and a finite standoff); without it, it would be ignored: "
                                 f"give {other} too, or neither")
        if given and self.standoff is None:
            raise ParameterError("pulse_energy and aperture_diameter count photoelectrons at a "
                                 "finite standoff; with the sensor at infinity they would be "
                                 "ignored: give standoff too")
        if not given:
            for name, default in PHOTON_ONLY.items():
                if getattr(self, name) != default:
                    raise ParameterError(
                        f"{name} ({getattr(self, name):g}) scales photoelectron counts, which "
                        "need pulse_energy and aperture_diameter (and a finite standoff); "
                        "without them it would be ignored: give them, or leave it out")

    @property
    def counts_photons(self) -> bool:
        """Whether received power comes out in photoelectrons (energy, aperture and a
        finite standoff all given)."""
        return (self.pulse_energy is not None and self.aperture_diameter is not None
                and self.standoff is not None)

    def photoelectrons_per_unit(self) -> float:
        """Photoelectrons per unit of the power sinogram (m²/sr): the aim point's fluence
        E_ref (J/m²) × the aperture's solid angle at D, π a²/4 / D² (sr) × optics ×
        quantum efficiency ÷ the photon energy hc/λ (J).

        Returns
        -------
        float
            Photoelectrons per unit of the power sinogram (per m²/sr).

        Raises
        ------
        ParameterError
            When the sensor does not count photons (``pulse_energy``,
            ``aperture_diameter`` and ``standoff`` not all given), or its beam is an
            unbounded flood.
        """
        if not self.counts_photons:
            raise ParameterError("photoelectrons need pulse_energy (J), aperture_diameter (m) "
                                 "and a finite standoff (m)")
        fluence = self.beam.reference_fluence(self.pulse_energy, self.standoff)
        solid = math.pi * self.aperture_diameter ** 2 / 4.0 / self.standoff ** 2
        photon = PLANCK * SPEED_OF_LIGHT / self.wavelength
        return fluence * solid * self.optics_transmission * self.quantum_efficiency / photon

    def describe(self) -> dict:
        """Every parameter, with its unit in its name (for result files).

        Returns
        -------
        dict
            ``standoff_m``, ``aim_m`` (a list), ``beam`` (the beam's own ``describe()``),
            ``extinction_per_m``, ``pulse_energy_J``, ``aperture_diameter_m``,
            ``optics_transmission``, ``quantum_efficiency`` and ``wavelength_m``.
        """
        return {"standoff_m": self.standoff, "aim_m": list(self.aim),
                "beam": self.beam.describe(), "extinction_per_m": self.extinction,
                "pulse_energy_J": self.pulse_energy,
                "aperture_diameter_m": self.aperture_diameter,
                "optics_transmission": self.optics_transmission,
                "quantum_efficiency": self.quantum_efficiency,
                "wavelength_m": self.wavelength}
