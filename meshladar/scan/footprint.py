"""A pulse's footprint: the sub-rays that sample its beam, each carrying a share of the
pulse's energy.

A :class:`ScanBeam` is the transmitted beam's angular profile about the pulse's direction:
``"gaussian"`` (irradiance ∝ exp(−2ρ²/θ_d²), ``divergence`` θ_d the 1/e² half-angle) or
``"tophat"`` (uniform within the half-angle θ_d). Its sub-rays sit on a sunflower (Vogel)
spiral in the profile's energy coordinate: sub-ray k of N at radius ρ_k with the profile's
radial CDF equal to (k + ½)/N and azimuth k × the golden angle, each carrying 1/N of the
energy. A Gaussian's tail beyond :data:`GAUSS_CUT` of its energy is dropped and the rest
scaled to the whole (a relative 1e-4).

How many: the error that matters is the share of a pulse that lands on one side of an edge
(a roof's ridge, a hole, a silhouette); the quadrature's share of every half-plane (36
directions, every offset) is compared with the profile's exact one (erfc for the Gaussian,
a circular segment for the top hat), and N is the smallest of :data:`SUB_RAY_COUNTS`
whose largest error is at most ``tol``. ``sub_rays=N`` fixes N instead. With
``divergence=0`` a pulse is one ray.

A flash array's pixel is a square of its IFOV, lit uniformly: an m × m grid of sub-rays
at the centres of equal cells; the share of an edge along a pixel's side is then within
1/(2m) of exact, so m = ⌈1/(2 tol)⌉, at most :data:`MAX_PIXEL_SIDE` (64 × 64 = 4096 sub-rays
a pixel, the most a scanning pulse's beam takes: ``tol`` ≥ 1/128). The beam's ``tol`` is
all a flash array takes from its :class:`ScanBeam`: its divergence, profile and
``sub_rays`` do not apply, and :func:`check_flash_beam` refuses them set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import erfc

from .._validate import check_choice, check_count, check_real
from ..errors import ParameterError

__all__ = ["ScanBeam", "PROFILES", "SUB_RAY_COUNTS", "GAUSS_CUT", "edge_error",
           "pixel_offsets", "MAX_PIXEL_SIDE", "check_flash_beam", "describe_pixels"]

#: The beams' angular profiles.
PROFILES = ("gaussian", "tophat")
#: The sub-ray counts ``tol`` chooses among.
SUB_RAY_COUNTS = (1, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096)
#: The fraction of a Gaussian beam's energy beyond the outermost sub-ray's reach.
GAUSS_CUT = 1e-4
#: The most sub-rays along a flash pixel's side: 64 × 64 = 4096 a pixel, as many as a
#: scanning pulse's beam takes at most (the last of :data:`SUB_RAY_COUNTS`).
MAX_PIXEL_SIDE = 64
_GOLDEN = math.pi * (3.0 - math.sqrt(5.0))
_EDGE_DIRECTIONS = 36


def _spiral(n, profile):
    """Unit-free offsets (n, 2) of the sunflower spiral: radii in units of θ_d."""
    u = (np.arange(n) + 0.5) / n
    if profile == "gaussian":
        rho = np.sqrt(-0.5 * np.log1p(-u * (1.0 - GAUSS_CUT)))
    else:
        rho = np.sqrt(u)
    phi = np.arange(n) * _GOLDEN
    if n == 1:
        rho = np.zeros(1)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi)], axis=1)


def _exact_share(s, profile):
    """The profile's energy beyond the line x = s (s in units of θ_d)."""
    if profile == "gaussian":
        return 0.5 * erfc(math.sqrt(2.0) * s)
    c = np.clip(s, -1.0, 1.0)
    return (np.arccos(c) - c * np.sqrt(1.0 - c * c)) / math.pi


def edge_error(offsets, profile):
    """The largest error of the sub-rays' equal shares in the energy beyond any straight
    edge, over 36 directions and every offset (the worst offsets are
    the sub-rays' own projections, approached from either side).

    Parameters
    ----------
    offsets : (n, 2) array_like
        Sub-ray offsets in units of the divergence θ_d.
    profile : str
        ``"gaussian"`` or ``"tophat"``.

    Returns
    -------
    float
        The largest |quadrature share − exact share|.
    """
    off = np.asarray(offsets, np.float64)
    n = len(off)
    ang = np.arange(_EDGE_DIRECTIONS) * math.pi / _EDGE_DIRECTIONS
    proj = np.sort(off @ np.stack([np.cos(ang), np.sin(ang)]), axis=0)     # (n, dirs)
    exact = _exact_share(proj, profile)
    above_just_below = (n - np.arange(n))[:, None] / n       # the share beyond s − 0
    above_just_above = (n - 1 - np.arange(n))[:, None] / n   # beyond s + 0
    err = np.maximum(np.abs(above_just_below - exact), np.abs(above_just_above - exact))
    return float(err.max())


def _pixel_side(tol, name="tol"):
    """m = ⌈1/(2 tol)⌉ of a flash pixel (module docstring), checked; ``name`` is the
    argument the messages name."""
    tol = check_real(name, tol, low=0.0, low_open=True, high=0.5)
    m = max(1, math.ceil(0.5 / tol - 1e-12))
    if m > MAX_PIXEL_SIDE:
        raise ParameterError(
            f"{name}={tol:g}: a flash pixel is sampled by m x m sub-rays, m = ceil(1/(2 tol)) "
            f"= {m} ({m * m} a pixel), more than {MAX_PIXEL_SIDE} x {MAX_PIXEL_SIDE} = "
            f"{MAX_PIXEL_SIDE ** 2}; give {name} >= {0.5 / MAX_PIXEL_SIDE:g}")
    return m


def pixel_offsets(tol):
    """A flash pixel's sub-ray offsets (module docstring).

    Parameters
    ----------
    tol : float
        The edge tolerance, in [1/128, 0.5]: m = ⌈1/(2 tol)⌉ sub-rays a side.

    Returns
    -------
    (m², 2) numpy.ndarray
        Cell centres in [−½, ½]², in units of the pixel's pitch.

    Raises
    ------
    ParameterError
        When ``tol`` is not in (0, 0.5], or needs more than :data:`MAX_PIXEL_SIDE`
        sub-rays a side (tol < 1/128), naming the count and the smallest ``tol`` allowed.
    """
    m = _pixel_side(tol)
    c = (np.arange(m) + 0.5) / m - 0.5
    y, z = np.meshgrid(c, c, indexing="ij")
    return np.stack([y.ravel(), z.ravel()], axis=1)


def check_flash_beam(beam):
    """Refuse a beam whose divergence, profile or ``sub_rays`` a flash array would ignore:
    its pixels are lit uniformly over their IFOV and sampled to ``beam.tol`` (module
    docstring), so only ``tol`` applies.

    Parameters
    ----------
    beam : ScanBeam
        The flash sensor's beam.

    Raises
    ------
    ParameterError
        Naming the field set away from its default (``divergence`` 0, ``profile``
        "gaussian", ``sub_rays`` None), its value and what a flash array uses; or a ``tol``
        that needs too many sub-rays a pixel (:func:`pixel_offsets`).
    """
    for name, default in (("divergence", 0.0), ("profile", "gaussian"), ("sub_rays", None)):
        value = getattr(beam, name)
        if value != default:
            raise ParameterError(
                f"beam.{name}={value!r} does not apply to a flash array: its pixels are lit "
                "uniformly over their IFOV, sampled by ceil(1/(2 tol)) x ceil(1/(2 tol)) "
                f"sub-rays to beam.tol={beam.tol:g}; leave {name} at its default "
                f"({default!r}) and set tol")
    _pixel_side(beam.tol, "beam.tol")


def describe_pixels(beam, ifov_deg):
    """What a flash array's pixels were sampled with, for the scan's ``info`` in place of
    the beam's own description (:meth:`ScanBeam.describe`).

    Parameters
    ----------
    beam : ScanBeam
        The flash sensor's beam (its ``tol`` only).
    ifov_deg : float
        A pixel's field of view, deg.

    Returns
    -------
    dict
        ``profile`` ("flash pixel": uniform over the pixel's IFOV), ``ifov_deg``, ``tol``,
        ``sub_rays`` (a pixel's, m²) and ``side`` (m).
    """
    m = _pixel_side(beam.tol)
    return {"profile": "flash pixel", "ifov_deg": ifov_deg, "tol": beam.tol,
            "sub_rays": m * m, "side": m}


@dataclass(frozen=True)
class ScanBeam:
    """A pulse's beam: its angular profile and how finely sub-rays sample it (module
    docstring).

    A flash array takes only ``tol`` from its beam: a flash scan with ``divergence``,
    ``profile`` or ``sub_rays`` set is refused (:func:`check_flash_beam`).

    Parameters
    ----------
    divergence : float
        Half-angle, rad, in [0, 0.5]: the 1/e² irradiance radius of a Gaussian, the edge of
        a top hat. 0: a single ray per pulse.
    profile : str
        ``"gaussian"`` (default) or ``"tophat"``.
    tol : float
        The largest error allowed in the share of a pulse's energy on either side of a
        straight edge, in (0, 0.5] (default 0.1: 32 sub-rays for either profile); chooses
        the number of sub-rays. A flash array's pixels are sampled to it too (m × m
        sub-rays a pixel, m = ⌈1/(2 tol)⌉ ≤ 64: ``tol`` ≥ 1/128).
    sub_rays : int, optional
        A fixed number of sub-rays (1 to 4096) instead of ``tol``.

    Raises
    ------
    ParameterError
        When a parameter is outside its range, or ``profile`` is unknown.
    """

    divergence: float = 0.0
    profile: str = "gaussian"
    tol: float = 0.1
    sub_rays: int | None = None

    def __post_init__(self):
        object.__setattr__(self, "divergence", check_real("divergence", self.divergence,
                                                          low=0.0, high=0.5))
        check_choice("profile", self.profile, PROFILES)
        object.__setattr__(self, "tol", check_real("tol", self.tol, low=0.0, low_open=True,
                                                   high=0.5))
        if self.sub_rays is not None:
            object.__setattr__(self, "sub_rays", check_count("sub_rays", self.sub_rays,
                                                             high=SUB_RAY_COUNTS[-1]))

    def offsets(self):
        """The sub-rays' angular offsets (n, 2), rad, about the pulse's direction (along
        two perpendicular axes), each carrying 1/n of the energy.

        Returns
        -------
        (n, 2) numpy.ndarray
            Offsets in radians; one row of zeros for a zero divergence.
        """
        if self.divergence == 0.0:
            return np.zeros((1, 2))
        if self.sub_rays is not None:
            return _spiral(self.sub_rays, self.profile) * self.divergence
        for n in SUB_RAY_COUNTS:
            unit = _spiral(n, self.profile)
            if edge_error(unit, self.profile) <= self.tol:
                return unit * self.divergence
        raise ParameterError(f"tol={self.tol:g} needs more than {SUB_RAY_COUNTS[-1]} "
                             "sub-rays per pulse; loosen it")

    def describe(self) -> dict:
        """The beam's parameters, with units in their names.

        Returns
        -------
        dict
            ``divergence_rad``, ``profile``, ``tol`` and ``sub_rays`` (the number used).
        """
        n = len(self.offsets())
        return {"divergence_rad": self.divergence, "profile": self.profile, "tol": self.tol,
                "sub_rays": n}
