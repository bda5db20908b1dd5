"""The mesh stage's records: :class:`Hits` (every view's first hits, geometry only) and
one view's hits as a worker returns them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._summary import table, text
from .errors import ParameterError
from .ladar import Ladar

__all__ = ["Hits", "ViewHits"]


@dataclass(frozen=True, eq=False)
class ViewHits:
    """One view's hits, as a worker returns them: k hits, ranges relative to the plane
    through the scene's (shifted) centre. The per-hit fields are :class:`Hits`' for that
    view, with the same shapes ((k,), or (k, 4) for ``spread``, ``bistatic`` and ``curve``;
    the last three may be None), frozen read-only; ``rays`` cast and ``back_face_hits`` are
    the view's counts.

    Parameters
    ----------
    range : (k,) numpy.ndarray
        Range of each hit relative to the plane through the scene's (shifted) centre,
        scene units.
    cos_theta, sin_theta : (k,) numpy.ndarray
        cos θ and sin θ of each hit's normal against the view direction, as in
        :class:`Hits`.
    material : (k,) numpy.ndarray
        Index of each hit's material in the scene's materials.
    spread : (k, 4) numpy.ndarray
        Footprint of each hit, as in :class:`Hits`.
    rays : int
        Rays cast in the view.
    back_face_hits : int
        Back-face hits in the view.
    bistatic : (k, 4) numpy.ndarray, optional
        Bistatic receiver angles, as in :class:`Hits` (default None).
    weight_factor : (k,) numpy.ndarray, optional
        Per-ray factor on F·area, as in :class:`Hits` (default None).
    curve : (k, 4) numpy.ndarray, optional
        Exact-normal slice footprints, as in :class:`Hits` (default None).
    receive_factor : (k,) numpy.ndarray, optional
        Received-power factor with a sensor, as in :class:`Hits` (default None).
    transverse : (k, 2) numpy.ndarray, optional
        Each hit's coordinates along the view's transverse axes (u, v) (default None).

    Raises
    ------
    ParameterError
        When ``range`` is not 1-D, or a per-hit field (an optional one unless None) does
        not have the shape above for k = ``len(range)``.
    """

    range: np.ndarray
    cos_theta: np.ndarray
    sin_theta: np.ndarray
    material: np.ndarray
    spread: np.ndarray
    rays: int
    back_face_hits: int
    bistatic: np.ndarray | None = None
    weight_factor: np.ndarray | None = None
    curve: np.ndarray | None = None
    receive_factor: np.ndarray | None = None
    transverse: np.ndarray | None = None

    def __post_init__(self):
        _freeze(self, np.shape(self.range)[0] if np.ndim(self.range) == 1 else -1,
                "ViewHits")


#: Per-hit fields of the hit records and their shapes (k hits); the optional ones may be None.
_FIELDS = {"view": (1,), "range": (1,), "cos_theta": (1,), "sin_theta": (1,),
           "material": (1,), "spread": (1, 4), "bistatic": (1, 4), "weight_factor": (1,),
           "curve": (1, 4), "receive_factor": (1,), "transverse": (1, 2)}
_OPTIONAL = ("bistatic", "weight_factor", "curve", "receive_factor", "transverse")


def _freeze(record, k, kind):
    """Check every per-hit field's shape against k hits and make it read-only in place."""
    for name, shape in _FIELDS.items():
        if not hasattr(record, name):
            continue
        a = getattr(record, name)
        if a is None and name in _OPTIONAL:
            continue
        a = np.asarray(a)
        want = (k,) + shape[1:]
        if k < 0 or a.shape != want:
            raise ParameterError(f"{kind}.{name} must have shape {want}; got {a.shape}")
        a.flags.writeable = False        # frozen in place: hits can be gigabytes
        object.__setattr__(record, name, a)


@dataclass(frozen=True, eq=False)
class Hits:
    """First hits of every ray, per view: geometry only, no materials' BRDFs.

    Per hit, k hits in all (arrays frozen read-only in place):

    ==================  ===========  =====================================================
    field               shape        meaning
    ==================  ===========  =====================================================
    ``view``            (k,) int32   index into the ladar's views
    ``range``           (k,)         range of the hit, −p·w (monostatic), scene units
    ``cos_theta``       (k,)         cos θ of the chosen normal against w; −1 marks a
                                     back-face hit that ``back_faces="ignore"`` blocks
    ``sin_theta``       (k,)         sin θ ≥ 0
    ``material``        (k,) int32   index into ``materials``
    ``spread``          (k, 4)       footprint: range half-widths along the two
                                     transverse axes (the second 0 in slice mode), and
                                     the hit facet's own range interval relative to the
                                     hit (≤ 0, ≥ 0)
    ``bistatic``        (k, 4)       with a bistatic receiver: cos θr, sin θr, cos α,
                                     sin α (cos θr = −1 where the receiver is occluded);
                                     else None
    ``weight_factor``   (k,)         per-ray factor on F·``area``: shading normals' area
                                     factor (cos θs/cos θg); with a sensor at finite
                                     standoff D the ray's cross-section at the hit,
                                     cos³α (R/D)², and the beam's relative irradiance;
                                     or None
    ``curve``           (k, 4)       exact-normal slice footprints on curved surfaces, or
                                     None
    ``receive_factor``  (k,)         with a sensor: what received power adds beyond
                                     cos θr, the receiver's (D/R)² and the two-way
                                     atmospheric transmission exp(−2σR); else None
    ==================  ===========  =====================================================

    Per view (n_views,): ``rays`` cast and ``back_face_hits``. Scalars: ``area`` (δA⊥ per
    ray), ``mode``, ``normals``; ``ladar`` and ``materials`` as traced; ``info`` the run's
    parameters.

    Attributes
    ----------
    view, range, cos_theta, sin_theta, material : (k,) numpy.ndarray
        Per-hit fields, as in the table above.
    spread : (k, 4) numpy.ndarray
        Per-hit footprint, as in the table above.
    rays, back_face_hits : (n_views,) numpy.ndarray
        Rays cast and back-face hits, per view; made read-only.
    area : float
        δA⊥, the area each ray stands for: the ray spacing δ in slice mode (per unit
        height), δ² in 3-D.
    mode : str
        The tracing mode, "slice" or "3d".
    normals : str
        The normals used, "flat", "smooth" or "exact".
    ladar : Ladar
        The views and range bins traced.
    materials : tuple
        The scene's materials, as traced; ``material`` indexes into it.
    bistatic, curve : (k, 4) numpy.ndarray or None
        Optional per-hit fields, as in the table above (default None).
    weight_factor, receive_factor : (k,) numpy.ndarray or None
        Optional per-hit fields, as in the table above (default None).
    info : dict
        The run's parameters (default empty).

    Raises
    ------
    ParameterError
        When ``view`` is not 1-D, or a per-hit field (an optional one unless None) does
        not have the shape above for k = ``len(view)``.
    """

    view: np.ndarray
    range: np.ndarray
    cos_theta: np.ndarray
    sin_theta: np.ndarray
    material: np.ndarray
    spread: np.ndarray
    rays: np.ndarray
    back_face_hits: np.ndarray
    area: float
    mode: str
    normals: str
    ladar: Ladar
    materials: tuple
    bistatic: np.ndarray = None
    weight_factor: np.ndarray = None
    curve: np.ndarray = None
    receive_factor: np.ndarray = None
    info: dict = field(default_factory=dict)

    def _summary(self):
        return (("hits", int(np.shape(self.view)[0])), ("n_views", self.ladar.n_views),
                ("mode", self.mode), ("normals", self.normals),
                ("materials", len(self.materials)), ("area", float(self.area)),
                ("bistatic", True if self.bistatic is not None else None),
                ("sensor", "standoff" if self.receive_factor is not None else None),
                ("back_face_hits", int(np.sum(self.back_face_hits)) or None))

    def __repr__(self) -> str:
        return text("Hits", *self._summary())

    def _repr_html_(self) -> str:
        return table("Hits", *self._summary())

    def __post_init__(self):
        _freeze(self, np.shape(self.view)[0] if np.ndim(self.view) == 1 else -1, "Hits")
        for name in ("rays", "back_face_hits"):
            a = np.asarray(getattr(self, name))
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    @property
    def size(self) -> int:
        return self.view.size
