"""The weighing of a run (:class:`Weighing`): coatings, footprint, radiometry and output
axes, checked against a :class:`~meshladar.raytrace.plan.TracePlan` before the first ray
(:meth:`Weighing.check`): every rule that only the pair of them decides is applied there,
not after the views have been traced."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_flag
from ..brdf import BRDF, is_builtin
from ..errors import ModelError, ParameterError
from ..motion import Motion
from ..raytrace.plan import TracePlan
from ..sensor import FloodBeam, check_radiometry

__all__ = ["Weighing"]


@dataclass(frozen=True, eq=False)
class Weighing:
    """How hits become bins.

    Attributes
    ----------
    materials : tuple of BRDF
        One coating per material index of the scene.
    footprint : bool
        Spread each ray's weight over the range interval its cell covers on a flat facet
        (parallel, monostatic rays only), or bin it at its hit (False).
    radiometry : {"paper", "power"}
        Eq. 8 (Σ F δA⊥) or received power (Σ F cos θr δA⊥).
    axes : tuple of str
        The output's coordinates (``("range",)`` for a sinogram; resolved returns name
        theirs, :data:`meshladar.returns.COORDINATES`).
    edges : tuple of (n + 1,) float64
        Bin edges per axis.
    motion : meshladar.motion.Motion or None
        The target's motion, for a Doppler axis.

    Raises
    ------
    ParameterError
        When ``radiometry`` is not ``"paper"`` or ``"power"``, or ``footprint`` is not a
        bool.
    """

    materials: tuple
    footprint: bool = False
    radiometry: str = "paper"
    axes: tuple = ("range",)
    edges: tuple = ()
    motion: Motion | None = None

    def __post_init__(self):
        check_radiometry(self.radiometry)
        check_flag("footprint", self.footprint)
        object.__setattr__(self, "materials", tuple(self.materials))
        object.__setattr__(self, "axes", tuple(self.axes))
        object.__setattr__(self, "edges", tuple(np.asarray(e, np.float64)
                                                for e in self.edges))

    @property
    def power(self) -> bool:
        """Received power (True) or the paper's Eq. 8 (False)."""
        return self.radiometry == "power"

    @property
    def resolved(self) -> bool:
        """Whether the output is resolved returns (any axes but range alone)."""
        return self.axes != ("range",)

    @property
    def compiled(self) -> bool:
        """Whether every coating has a compiled kernel (``kernel_params``: SR, Lambertian),
        so the compiled loops can evaluate F at each hit."""
        return all(m.kernel_params is not None for m in self.materials)

    @property
    def compiled_bistatic(self) -> bool:
        """Whether every coating is a built-in model with a compiled kernel (SR,
        Lambertian), so the fused bistatic loop can evaluate F(w, w_r) at each face's first
        hit (a user's ``kernel_params`` row speaks for its monostatic F only)."""
        return self.compiled and all(is_builtin(m) for m in self.materials)

    def check(self, plan: TracePlan) -> None:
        """Refuse every combination of this weighing and ``plan`` that no ray can honour,
        before the first ray is cast; returns nothing.

        Parameters
        ----------
        plan : TracePlan
            The run's validated plan (its ``sensor`` as given and its ``receivers``).

        Raises
        ------
        ParameterError
            When footprint binning meets a sensor or a bistatic receiver; when the
            plan's sensor has a non-zero extinction, or counts photoelectrons
            (``counts_photons``), under ``radiometry="paper"``; when it counts
            photoelectrons with an unbounded flood beam (``FloodBeam(radius=None)``).
        ModelError
            When the plan has bistatic receivers and a coating has no ``bistatic``
            evaluation of its own.
        """
        if self.footprint and plan.sensor is not None:
            raise ParameterError("footprint binning is for parallel rays without a sensor; "
                                 "use footprint=False with a sensor")
        if self.footprint and plan.receivers is not None:
            raise ParameterError("footprint binning is monostatic only; use footprint=False "
                                 "with a bistatic receiver")
        if plan.receivers is not None:
            _check_bistatic(self.materials)
        if plan.sensor is not None:
            _check_sensor_radiometry(plan.sensor, self.radiometry)


def _check_bistatic(materials):
    """A bistatic receiver weighs F(w, w_r): every coating must evaluate it."""
    for k, m in enumerate(materials):
        if type(m).bistatic is BRDF.bistatic:
            raise ModelError(f"materials[{k}]: {type(m).__name__} has no bistatic evaluation: "
                             "define bistatic() to use it with a bistatic receiver (built in: "
                             "SandfordRobertson, Lambertian, Phong, GGX), or drop receiver")


def _check_sensor_radiometry(sensor, radiometry):
    """A sensor's atmosphere and photon counts are received power; counting photons needs
    the flood's extent."""
    if sensor.extinction > 0 and radiometry != "power":
        raise ParameterError(f"extinction ({sensor.extinction:g} per m) attenuates the "
                             "received power: use radiometry='power' (Eq. 8 has no "
                             "receiver; the paper convention ignores the atmosphere); got "
                             f"radiometry={radiometry!r}")
    if sensor.counts_photons:
        if radiometry != "power":
            raise ParameterError("a sensor with pulse_energy and aperture_diameter counts "
                                 "photoelectrons of received power: use "
                                 "radiometry='power' (or drop them for Eq. 8); got "
                                 f"radiometry={radiometry!r}")
        if isinstance(sensor.beam, FloodBeam) and sensor.beam.radius is None:
            raise ParameterError("photoelectrons need the flood's extent: give "
                                 "FloodBeam(radius=...) (m at the aim point), or a "
                                 "GaussianBeam; got sensor.beam=FloodBeam(radius=None)")
