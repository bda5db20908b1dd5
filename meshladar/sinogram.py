"""The sinogram: range profiles of many views, the data every forward model produces.

A :class:`Sinogram` is what ``simulate`` returns and what a user wraps around measured data.
Its values are bin integrals (not densities): ``values[i, k]`` is the return of view i
integrated over range bin k, ``[bin_edges[k], bin_edges[k + 1])``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import plotting
from ._summary import table, text
from ._validate import (azimuths_deg, check_views_agree, finite_array, readonly_copy,
                        unit_vectors)
from .errors import ParameterError

__all__ = ["Sinogram", "RecordInfo", "TYPED_INFO_KEYS", "check_sinogram", "split_info"]

#: The record keys that were undeclared ``info`` entries and are now typed fields of
#: :class:`Sinogram` and :class:`~meshladar.waveforms.Waveforms`; ``info[key]`` still reads
#: them for one release.
TYPED_INFO_KEYS = ("radiometry", "units")


class RecordInfo(dict):
    """A read-only view of a record's ``info``: its free-form provenance merged with its typed
    fields (``radiometry``, ``units``), so that ``info["radiometry"]`` keeps reading the field
    for one release (the habit of trimesh's ``MassProperties.__getitem__``). Mutation raises
    TypeError; it pickles and JSON-encodes as a plain dict."""

    __slots__ = ()

    def _read_only(self, *args, **kwargs):
        """Refuse any change: a record's ``info`` is read-only (``update``, ``pop``,
        ``popitem``, ``clear``, ``setdefault``, item assignment and deletion, ``|=``).

        Parameters
        ----------
        *args, **kwargs
            Whatever the dict method takes; ignored.

        Raises
        ------
        TypeError
            Always; build a new record with ``info=dict(record.info, key=value)``.
        """
        raise TypeError("a record's info is read-only; build a new record with "
                        "info=dict(record.info, key=value)")

    __setitem__ = __delitem__ = _read_only
    update = pop = popitem = clear = setdefault = __ior__ = _read_only

    def __reduce__(self):
        return (RecordInfo, (dict(self),))

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self


def split_info(record, info, *, keep_none=False) -> dict:
    """Move the typed keys of ``info`` (a mapping) onto ``record``'s fields of the same name
    (a frozen dataclass with ``radiometry`` and ``units``) and set
    ``record.info`` to the merged read-only :class:`RecordInfo`. Returns the provenance (the
    free-form rest) as a new dict. An unset typed field shows in ``info`` as None when the
    given info held the key, or with ``keep_none`` (the waveforms' info always held both).

    Parameters
    ----------
    record : object
        A frozen dataclass with ``radiometry``, ``units`` and ``info`` fields
        (:class:`Sinogram`, :class:`~meshladar.waveforms.Waveforms`); changed in place.
    info : Mapping
        The info given. When it is a :class:`RecordInfo` (the record's own, passed on by
        ``dataclasses.replace``) a field set on ``record`` wins over its typed key;
        otherwise a typed key given in ``info`` wins over the field.
    keep_none : bool
        Show both typed keys in ``record.info`` even when None (default False).
        Keyword-only.

    Returns
    -------
    dict
        The free-form provenance: ``info`` without the keys in :data:`TYPED_INFO_KEYS`.

    Raises
    ------
    ParameterError
        When ``info`` is not a mapping, or a typed value is neither a string nor None.
    """
    if not isinstance(info, Mapping):
        raise ParameterError(f"info must be a dict; got {type(info).__name__}")
    # dataclasses.replace hands both the old fields and the old info: a record's own
    # RecordInfo yields to a field given anew (replace(sino, units=...)), a new info dict
    # overrides the old field (replace(sino, info=dict(sino.info, units=...)), as before)
    field_wins = isinstance(info, RecordInfo)
    rest = dict(info)
    merged = {}
    for key in TYPED_INFO_KEYS:
        present = key in rest
        given, old = getattr(record, key), rest.pop(key, None)
        value = given if given is not None and (field_wins or old is None) else old
        if value is not None and not isinstance(value, str):
            raise ParameterError(f"{key} must be a string or None; got {value!r}")
        object.__setattr__(record, key, value)
        if value is not None or keep_none or present:
            merged[key] = value
    object.__setattr__(record, "info", RecordInfo(rest, **merged))
    return rest


def check_sinogram(name: str, value):
    """``value`` if it is a meshladar.Sinogram, else a ParameterError.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        The value to check.

    Returns
    -------
    Sinogram
        ``value``, unchanged.

    Raises
    ------
    ParameterError
        When ``value`` is not a :class:`Sinogram` (or a subclass).
    """
    if not isinstance(value, Sinogram):
        raise ParameterError(f"{name} must be a meshladar.Sinogram; got {type(value).__name__}")
    return value


@dataclass(frozen=True, eq=False)
class Sinogram:
    """Range-resolved returns of many views.

    All arrays are stored as read-only float64 copies.

    Parameters
    ----------
    values : (n_views, n_bins) array_like, float64
        Bin integrals over the visible surface: of F(θ) cos θ dA (paper Eq. 8,
        ``radiometry="paper"``) or of the received power F cos θ_i cos θ_r dA
        (``"power"``), in scene units of area (length in 2D) times 1/sr, or photoelectrons
        with a sensor that counts them (``units``).
    angles_deg : (n_views,) array_like, keyword-only
        View angles φ in degrees, about the z axis: the ladar looks from
        w = (cos φ, sin φ, 0) toward the scene; φ = 90° is the paper's Fig. 1. Optional
        with ``view_vectors`` (default: their azimuths).
    bin_edges : (n_bins + 1,) array_like, keyword-only
        Strictly increasing range bin edges; range r = −p·w grows away from the ladar.
    model : str, keyword-only
        Which forward model made it ("analytic", "mesh", "pixel"), or "measured".
    view_vectors : (n_views, 3) array_like, keyword-only, optional
        The view directions when they are not all about the z axis (mesh model).
    info : dict, keyword-only
        Free-form provenance (run parameters, error estimates); not compared. Stored as a
        read-only :class:`RecordInfo` that also shows the typed fields below, so
        ``info["radiometry"]`` still reads for one release; a ``"radiometry"`` or
        ``"units"`` key given here fills the field of that name.
    radiometry : str, keyword-only, optional
        The convention of the values: ``"paper"`` (Eq. 8) or ``"power"``; None when unknown
        (measured data).
    units : str, keyword-only, optional
        The values' units when not the convention's own (``"photoelectrons"``).

    Raises
    ------
    ParameterError
        When neither ``angles_deg`` nor ``view_vectors`` is given; an array is not finite
        real numbers; ``values`` is not 2-D with at least one
        view and one bin; ``angles_deg`` has not one angle per view; ``bin_edges`` has not
        n_bins + 1 strictly increasing entries; ``model`` is not a string; ``view_vectors``
        is not (n_views, 3) non-zero vectors (normalised to unit length), or an angle
        differs from its vector's azimuth by more than
        :data:`meshladar.precision.ANGLE_TOL_DEG` (vectors along ±z excepted); ``info`` is not
        a mapping; or ``radiometry`` or ``units`` is neither a string nor None.
    """

    values: np.ndarray
    angles_deg: np.ndarray = field(default=None, kw_only=True)
    bin_edges: np.ndarray = field(kw_only=True)
    model: str = field(default="measured", kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)
    view_vectors: np.ndarray = field(default=None, kw_only=True, repr=False)
    radiometry: str | None = field(default=None, kw_only=True)
    units: str | None = field(default=None, kw_only=True)

    def __post_init__(self):
        values = finite_array("values", self.values)
        given = self.angles_deg
        if given is None and self.view_vectors is None:
            raise ParameterError("give angles_deg or view_vectors; got neither")
        if given is None:                       # the views' azimuths
            vec = finite_array("view_vectors", self.view_vectors)
            if vec.ndim != 2 or vec.shape[1] != 3:
                raise ParameterError(f"view_vectors must have shape (n_views, 3); got "
                                     f"{vec.shape}")
            given = azimuths_deg(vec)
        angles = finite_array("angles_deg", given)
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
        split_info(self, self.info)
        if not isinstance(self.model, str):
            raise ParameterError(f"model must be a string; got {self.model!r}")
        if self.view_vectors is None:
            phi = np.deg2rad(angles)
            vec = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1)
        else:
            vec = finite_array("view_vectors", self.view_vectors)
            if vec.shape != (values.shape[0], 3):
                raise ParameterError(f"view_vectors must have shape ({values.shape[0]}, 3); got "
                                     f"{vec.shape}")
            vec = unit_vectors("view_vectors", vec)
            check_views_agree(angles, vec)
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
        """(n_views,) total return of each view: the sum of its bins.

        Returns
        -------
        (n_views,) numpy.ndarray
            ``values.sum(axis=1)``, in the values' units.
        """
        return self.values.sum(axis=1)

    @property
    def provenance(self) -> dict:
        """The free-form part of :attr:`info` (without the typed fields), as a new dict."""
        return {k: v for k, v in self.info.items() if k not in TYPED_INFO_KEYS}

    def plot(self, *, log=None):
        """A quick look (:func:`meshladar.viz.quick.sinogram`, through
        :mod:`meshladar.plotting`): a matplotlib Figure; ``log`` (default: when the values
        span more than three decades) a log colour scale.

        Parameters
        ----------
        log : bool, optional
            Log colour scale; None (default): when the positive values' largest is more
            than 1e3 times their smallest. Keyword-only.

        Returns
        -------
        matplotlib.figure.Figure
            Views against range, and the views' totals.

        Raises
        ------
        ImportError
            When the ``viz`` extra is not installed.
        """
        return plotting.plot(self, log=log)

    def _summary(self):
        return (("model", self.model), ("n_views", self.n_views), ("n_bins", self.n_bins),
                ("range", (float(self.bin_edges[0]), float(self.bin_edges[-1]))),
                ("max", float(self.values.max(initial=0.0))),
                ("radiometry", self.radiometry), ("units", self.units),
                ("views", "about z, w = (cos φ, sin φ, 0)" if self.planar else
                 "3-D directions w"), ("ranges", "r = −p·w"),
                ("preprocess", self.info.get("preprocess")))

    def __repr__(self) -> str:
        return text("Sinogram", *self._summary())

    def _repr_html_(self) -> str:
        return table("Sinogram", *self._summary())
