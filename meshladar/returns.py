"""Returns binned by one to three coordinates of each hit (:class:`Returns`), the record
that :func:`meshladar.forward.resolved.resolve` makes: range (the sinogram's), cross-range,
elevation and Doppler."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._summary import table, text
from ._validate import check_count, check_real, finite_array, readonly_copy, short
from .errors import ParameterError
from .noise import draw_noise, Noise
from .sinogram import Sinogram

__all__ = ["COORDINATES", "Returns"]

#: The coordinates a view's returns can be binned by (:mod:`meshladar.forward.resolved`).
COORDINATES = ("range", "cross_range", "elevation", "doppler")
#: The longest dwell (s) a realisation integrates background over: at the noise's highest
#: rates (1e15 s⁻¹) its mean count stays within numpy's Poisson range.
MAX_DWELL_S = 1e3

_UNITS = {"range": "m", "cross_range": "m", "elevation": "m", "doppler": "Hz"}


@dataclass(frozen=True, eq=False)
class Returns:
    """Returns of many views binned by one to three coordinates.

    ``values`` (n_views, n_0[, n_1[, n_2]]): per cell, the sum of the weights of the rays whose
    first hit lies in it (bin integrals, as a sinogram's); ``axes`` the coordinates' names
    (:data:`COORDINATES`), ``edges`` their bin edges (in ``units``); ``angles_deg`` and
    ``view_vectors`` the views; ``info`` the run's parameters (radiometry, units, motion).

    Parameters
    ----------
    values : (n_views, n_0[, n_1[, n_2]]) array_like
        Bin integrals per view and cell; finite, stored as a read-only float64 copy.
    axes : tuple of str
        The coordinates' names, one per axis of ``values`` after the first, from
        :data:`COORDINATES` (``units`` reads m for the lengths, Hz for ``"doppler"``).
        Keyword-only.
    edges : tuple of array_like
        Per axis, its (n_k + 1,) bin edges in that axis' unit; finite, stored as read-only
        float64 copies. Keyword-only.
    angles_deg : (n_views,) array_like
        View angles, degrees; stored as a read-only float64 copy, not checked.
        Keyword-only.
    view_vectors : (n_views, 3) array_like
        View directions; stored as a read-only float64 copy, not checked. Keyword-only.
    info : dict
        The run's parameters (default empty; copied). ``info["units"]`` is
        ``"photoelectrons"`` for returns that :meth:`realise` takes. Keyword-only.

    Raises
    ------
    ParameterError
        When ``axes`` is not a tuple or list of distinct names from :data:`COORDINATES`,
        ``values`` or an edge array is not finite, or the shapes disagree: ``values`` not
        1 + len(axes) dimensional, not one edge array per axis, or an edge array not one
        longer than its axis.
    """

    values: np.ndarray
    axes: tuple = field(kw_only=True)
    edges: tuple = field(kw_only=True)
    angles_deg: np.ndarray = field(kw_only=True)
    view_vectors: np.ndarray = field(kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)

    def __post_init__(self):
        _check_axes(self.axes)
        v = finite_array("values", self.values)
        edges = tuple(readonly_copy(finite_array(f"edges[{i}]", e))
                      for i, e in enumerate(self.edges))
        if v.ndim != 1 + len(self.axes) or len(edges) != len(self.axes) or any(
                e.shape != (n + 1,) for e, n in zip(edges, v.shape[1:])):
            raise ParameterError(f"values must be (n_views, one size per axis) with edges one "
                                 f"longer per axis; got {v.shape}, axes {self.axes}")
        object.__setattr__(self, "values", readonly_copy(v))
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "axes", tuple(self.axes))
        object.__setattr__(self, "angles_deg", readonly_copy(self.angles_deg))
        object.__setattr__(self, "view_vectors", readonly_copy(self.view_vectors))
        object.__setattr__(self, "info", dict(self.info))

    @property
    def units(self) -> tuple:
        return tuple(_UNITS[a] for a in self.axes)

    def centers(self, axis) -> np.ndarray:
        """Bin centres of ``axis`` (a name or an index).

        Parameters
        ----------
        axis : str or int
            A name in :attr:`axes`, or its index among them (0 for the first binned axis).

        Returns
        -------
        (n_k,) numpy.ndarray
            Mid-points of the axis' bin edges, in its unit.

        Raises
        ------
        ParameterError
            When ``axis`` is a name not in :attr:`axes`.
        """
        e = self.edges[self._index(axis)]
        return 0.5 * (e[1:] + e[:-1])

    def _index(self, axis):
        if isinstance(axis, str):
            if axis not in self.axes:
                raise ParameterError(f"axis must be one of {self.axes}; got {axis!r}")
            return self.axes.index(axis)
        return int(axis)

    def total(self) -> np.ndarray:
        """(n_views,) each view's total return.

        Returns
        -------
        (n_views,) numpy.ndarray
            The sum of each view's cells.
        """
        return self.values.reshape(self.values.shape[0], -1).sum(axis=1)

    def marginal(self, axis) -> np.ndarray:
        """(n_views, n) the returns binned by ``axis`` alone (summed over the others).

        Parameters
        ----------
        axis : str or int
            A name in :attr:`axes`, or its index among them.

        Returns
        -------
        (n_views, n) numpy.ndarray
            ``values`` summed over every other binned axis (``values`` itself when there is
            one axis); n the axis' number of bins.

        Raises
        ------
        ParameterError
            When ``axis`` is a name not in :attr:`axes`.
        """
        k = self._index(axis)
        others = tuple(1 + j for j in range(len(self.axes)) if j != k)
        return self.values.sum(axis=others) if others else self.values

    def sinogram(self):
        """The range marginal as a :class:`~meshladar.sinogram.Sinogram`.

        Returns
        -------
        Sinogram
            ``model="mesh"``, values :meth:`marginal` ``("range")``, the range axis' edges as
            ``bin_edges``, the views' angles, their vectors unless all lie in the x-y plane,
            and a copy of ``info``.

        Raises
        ------
        ParameterError
            When ``"range"`` is not one of the axes.
        """
        planar = bool(np.all(self.view_vectors[:, 2] == 0.0))
        return Sinogram(self.marginal("range"), angles_deg=self.angles_deg,
                        bin_edges=self.edges[self.axes.index("range")], model="mesh",
                        view_vectors=None if planar else self.view_vectors,
                        info=dict(self.info))

    def realise(self, noise, n=1, *, seed=None, dwell=0.0):
        """``n`` noise realisations, shape ``(n, *values.shape)``
        (:class:`meshladar.noise.Noise`), each cell integrating background and dark counts
        over ``dwell`` seconds (its range gate, at most :data:`MAX_DWELL_S`); the returns
        must count photoelectrons (a sensor that counts them, or :meth:`scaled`).

        Parameters
        ----------
        noise : meshladar.noise.Noise
            The receiver's noise.
        n : int
            Number of realisations, ≥ 1 (default 1).
        seed : int, sequence of int or None
            Seed of numpy's default generator (default None: fresh entropy). Keyword-only.
        dwell : float
            Each cell's integration time, s, in [0, :data:`MAX_DWELL_S`] (default 0.0);
            must be > 0 when the noise has background or dark counts. Keyword-only.

        Returns
        -------
        (n, n_views, n_0, ...) numpy.ndarray
            float64 draws in the noise's output units
            (:func:`meshladar.noise.draw_noise`).

        Raises
        ------
        ParameterError
            When ``noise`` is not a Noise, ``info["units"]`` is not ``"photoelectrons"``,
            ``dwell`` is out of range or 0 with background or dark counts, ``n`` is not an
            integer ≥ 1, ``seed`` is invalid, or the draws would pass meshladar's
            allocation cap or mean-count limit.

        Warns
        -----
        MeshladarWarning
            When quantised draws clip at the digitiser's top code.
        """
        if not isinstance(noise, Noise):
            raise ParameterError(f"noise must be a meshladar.noise.Noise; got "
                                 f"{type(noise).__name__}")
        if self.info.get("units") != "photoelectrons":
            raise ParameterError(f"noise counts photoelectrons; these returns are in "
                                 f"{self.info.get('units')!r}: convert with scaled(factor)")
        dwell = check_real("dwell", dwell, low=0.0, high=MAX_DWELL_S)
        if dwell == 0 and (noise.background_rate > 0 or noise.dark_rate > 0):
            raise ParameterError("background and dark counts accumulate over each cell's "
                                 "dwell time: give dwell (s), e.g. its range gate")
        return draw_noise(noise, self.values, dwell, check_count("n", n), seed)

    def scaled(self, factor, units="photoelectrons") -> "Returns":
        """The same returns times ``factor``, in ``units``.

        Parameters
        ----------
        factor : float
            Multiplier, finite and > 0 (e.g. photoelectrons per unit of relative power).
        units : str or None
            The scaled values' units, stored as ``info["units"]`` (default
            ``"photoelectrons"``); photoelectrons are not scaled to photoelectrons again
            (a double count).

        Returns
        -------
        Returns
            A new record: values × ``factor``, the same axes, edges and views, and ``info``
            with ``units`` and ``scaled_by`` (the factor) set.

        Raises
        ------
        ParameterError
            When ``factor`` is not a finite number > 0, when the returns already count
            photoelectrons and ``units`` is ``"photoelectrons"``, or when ``units`` is
            neither a string nor None.
        """
        f = check_real("factor", factor, low=0.0, low_open=True)
        if units is not None and not isinstance(units, str):
            raise ParameterError(f"units must be a string or None; got {short(units)}")
        if self.info.get("units") == "photoelectrons" and units == "photoelectrons":
            raise ParameterError("these returns already count photoelectrons (their sensor "
                                 "counted them): scaling them to photoelectrons again would "
                                 "count twice; scale returns of relative power, or give "
                                 "the units the factor converts to")
        return Returns(self.values * f, axes=self.axes, edges=self.edges,
                       angles_deg=self.angles_deg, view_vectors=self.view_vectors,
                       info=dict(self.info, units=units, scaled_by=f))

    def _summary(self):
        return (("n_views", self.values.shape[0]),
                *((a, f"[{e[0]:.4g}, {e[-1]:.4g}] {u} in {e.size - 1}")
                  for a, e, u in zip(self.axes, self.edges, self.units)),
                ("units", self.info.get("units")), ("radiometry", self.info.get("radiometry")))

    def __repr__(self) -> str:
        return text("Returns", *self._summary())

    def _repr_html_(self) -> str:
        return table("Returns", *self._summary())


def _check_axes(axes):
    """``axes`` must be a tuple or list of distinct names from :data:`COORDINATES`."""
    if not isinstance(axes, (tuple, list)) or not all(
            isinstance(a, str) and a in COORDINATES for a in axes):
        raise ParameterError(f"axes must be a tuple of names from {COORDINATES}; got "
                             f"{short(axes)}")
    if len(set(axes)) != len(axes):
        raise ParameterError(f"axes must be different coordinates; got {short(axes)}")
