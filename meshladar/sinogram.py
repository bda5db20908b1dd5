"""The sinogram: range profiles of many views, the data every forward model produces.

A :class:`Sinogram` is what ``simulate`` returns and what a user wraps around measured data.
Its values are bin integrals (not densities): ``values[i, k]`` is the return of view i
integrated over range bin k, ``[bin_edges[k], bin_edges[k + 1])``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ._validate import finite_array, readonly_copy, unit_vectors
from .errors import ParameterError

__all__ = ["Sinogram"]


@dataclass(frozen=True, eq=False)
class Sinogram:
    """Range-resolved returns of many views.

    Parameters
    ----------
    values : (n_views, n_bins) array_like, float64
        Bin integrals over the visible surface: of F(θ) cos θ dA (DESIGN.md, paper Eq. 8,
        ``info["radiometry"] = "paper"``) or of the received power F cos θ_i cos θ_r dA
        (``"power"``), in scene units of area (length in 2D) times 1/sr, or photoelectrons
        with a sensor that counts them (``info["units"]``).
    angles_deg : (n_views,) array_like, keyword-only
        View angles φ in degrees, about the z axis: the ladar looks from
        w = (cos φ, sin φ, 0) toward the scene; φ = 90° is the paper's Fig. 1.
    bin_edges : (n_bins + 1,) array_like, keyword-only
        Strictly increasing range bin edges; range r = −p·w grows away from the ladar.
    model : str, keyword-only
        Which forward model made it ("analytic", "mesh", "pixel"), or "measured".
    view_vectors : (n_views, 3) array_like, keyword-only, optional
        The view directions when they are not all about the z axis (mesh model).
    info : dict, keyword-only
        Free-form metadata (run parameters, error estimates); not compared.

    All arrays are stored as read-only float64 copies.
    """

    values: np.ndarray
    angles_deg: np.ndarray = field(kw_only=True)
    bin_edges: np.ndarray = field(kw_only=True)
    model: str = field(default="measured", kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)
    view_vectors: np.ndarray = field(default=None, kw_only=True, repr=False)

    def __post_init__(self):
        values = finite_array("values", self.values)
        angles = finite_array("angles_deg", self.angles_deg)
        edges = finite_array("bin_edges", self.bin_edges)
        if values.ndim != 2 or 0 in values.shape:
            raise ParameterError(f"values must be a 2-D array (n_views, n_bins) of at least one "
                                 f"view and one bin; got shape {values.shape}")
        if angles.ndim != 1 or angles.size != values.shape[0]:
            raise ParameterError(f"angles_deg must have one angle per view (row of values): "
                                 f"{values.shape[0]}; got shape {angles.shape}")
        if edges.ndim != 1 or edges.size != values.shape[1] + 1:
            raise ParameterError(f"bin_edges must have n_bins + 1 = {values.shape[1] + 1} "
                                 f"entries; got shape {edges.shape}")
        if np.any(np.diff(edges) <= 0):
            raise ParameterError("bin_edges must be strictly increasing")
        object.__setattr__(self, "values", readonly_copy(values))
        object.__setattr__(self, "angles_deg", readonly_copy(angles))
        object.__setattr__(self, "bin_edges", readonly_copy(edges))
        if not isinstance(self.info, dict):
            raise ParameterError(f"info must be a dict; got {type(self.info).__name__}")
        if not isinstance(self.model, str):
            raise ParameterError(f"model must be a string; got {self.model!r}")
        object.__setattr__(self, "info", dict(self.info))
        if self.view_vectors is None:
            phi = np.deg2rad(angles)
            vec = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1)
        else:
            vec = finite_array("view_vectors", self.view_vectors)
            if vec.shape != (values.shape[0], 3):
                raise ParameterError(f"view_vectors must have shape ({values.shape[0]}, 3); got "
                                     f"{vec.shape}")
            vec = unit_vectors("view_vectors", vec)
        object.__setattr__(self, "view_vectors", readonly_copy(vec))

    @property
    def shape(self) -> tuple[int, int]:
        """(n_views, n_bins)."""
        return self.values.shape

    @property
    def planar(self) -> bool:
        """True when every view lies in the x-y plane (views about the z axis)."""
        return bool(np.all(self.view_vectors[:, 2] == 0.0))

    @property
    def n_views(self) -> int:
        return self.values.shape[0]

    @property
    def n_bins(self) -> int:
        return self.values.shape[1]

    @cached_property
    def bin_centers(self) -> np.ndarray:
        """(n_bins,) mid-points of the range bins."""
        return 0.5 * (self.bin_edges[1:] + self.bin_edges[:-1])

    @cached_property
    def bin_widths(self) -> np.ndarray:
        """(n_bins,) widths of the range bins."""
        return np.diff(self.bin_edges)

    def total(self) -> np.ndarray:
        """(n_views,) total return of each view: the sum of its bins."""
        return self.values.sum(axis=1)

    def plot(self, *, log=None):
        """A quick look (:func:`meshladar.viz.quick.sinogram`): a matplotlib Figure; ``log``
        (default: when the values span more than three decades) a log colour scale."""
        from .viz.quick import sinogram

        return sinogram(self, log=log)

    def _summary(self):
        return (("model", self.model), ("n_views", self.n_views), ("n_bins", self.n_bins),
                ("range", (float(self.bin_edges[0]), float(self.bin_edges[-1]))),
                ("max", float(self.values.max(initial=0.0))),
                ("radiometry", self.info.get("radiometry")), ("units", self.info.get("units")),
                ("views", "about z, w = (cos φ, sin φ, 0)" if self.planar else
                 "3-D directions w"), ("ranges", "r = −p·w"),
                ("preprocess", self.info.get("preprocess")))

    def __repr__(self) -> str:
        from ._summary import text

        return text("Sinogram", *self._summary())

    def _repr_html_(self) -> str:
        from ._summary import table

        return table("Sinogram", *self._summary())
