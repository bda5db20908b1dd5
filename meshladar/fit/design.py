"""View design: which of the candidate views constrain the coatings best (greedy
D-optimal design on the Fisher information of Poisson counts)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from .. import plotting
from .._validate import check_count, check_real, short
from ..errors import ParameterError
from ..hits import Hits
from ._irls import check_scale
from ._params import _jacobian, _resolve_params
from ._tables import _table
from .kernels import CoatingKernel, coating_kernel

__all__ = ["ViewDesign", "design_views"]

#: design_views' default ``samples`` for a Scene (pieces per analytic boundary, or rays per
#: range-bin width of a mesh Scene); Hits carry their own rays and take no samples.
DESIGN_SAMPLES = 4096


@dataclass(frozen=True, eq=False)
class ViewDesign:
    """The result of :func:`design_views`.

    Attributes
    ----------
    chosen : (budget,) int array
        Indices of the chosen views, in the order the greedy search added them.
    angles_deg : (n_views,) array
        Every candidate view's angle.
    information : (n_views,) array
        Each candidate alone: log det of its scaled Fisher information (with a small
        ridge), the view's own worth.
    names : tuple of str
        "part.parameter" of each of the n free parameters.
    stderr_designed, stderr_uniform : (n,) arrays
        Parameter σ from the chosen views and from ``budget`` evenly spaced views, in
        each parameter's own units (the inverse of the summed Fisher information plus the
        ridge).
    uniform : (budget,) int array
        The evenly spaced views: indices round(k · n_views / budget), k = 0 … budget − 1.
    """

    chosen: np.ndarray
    angles_deg: np.ndarray
    information: np.ndarray
    names: tuple
    stderr_designed: np.ndarray
    stderr_uniform: np.ndarray
    uniform: np.ndarray

    def plot(self, **options):
        """A quick look (:func:`meshladar.viz.fitting.design_figure`, through
        :mod:`meshladar.plotting`): a matplotlib Figure.

        Parameters
        ----------
        **options
            Passed to the drawing function unchanged (``design_figure`` takes none at
            present, so any option raises TypeError).

        Returns
        -------
        matplotlib.figure.Figure
            Each view's own information against its angle, the chosen and evenly spaced
            views marked, and each parameter's σ from both (no pyplot state touched).

        Raises
        ------
        ImportError
            When the ``viz`` extra (matplotlib) is not installed.
        """
        return plotting.plot(self, **options)


def design_views(geometry, budget, *, ladar=None, parts=None, free=None, materials=None,
                 photons_per_unit=None, samples=DESIGN_SAMPLES):
    """Which ``budget`` of the candidate views constrain the coatings best: greedy
    D-optimal design on the Fisher information of Poisson counts (each step adds the view
    that most raises log det F of the chosen set), compared with evenly spaced views.

    The Fisher information of view v is Σ over its bins of J_b J_bᵀ / m_b, J the model's
    derivatives in counts with each parameter measured in units of its range (the width
    of its bounds: SR's valid ranges, or |value| for an unbounded one), m_b the bin's
    expected counts (at least 1e-9 of the brightest). A ridge of 1e-9 times the mean
    diagonal of the total information keeps log det finite.

    Parameters
    ----------
    geometry : CoatingKernel, Scene or Hits
        The candidates are its views (a Scene needs ``ladar``). A Scene goes through
        :func:`coating_kernel` with ``samples``, Hits through ``coating_kernel(hits)``
        (they carry their own rays: ``samples`` is not passed).
    budget : int
        Views to choose, in [1, n_views].
    ladar : Ladar, optional
        The candidate views and bins of a Scene (unused with a CoatingKernel).
    parts, free
        As :func:`fit_coatings`.
    materials : dict, optional
        part → BRDF, the coatings the design is for (default the geometry's).
    photons_per_unit : float, optional
        Counts per unit of the sinogram (default: 1e5 counts in the brightest bin), > 0;
        the brightest bin must then hold 1 to 1e15 counts.
    samples : int, float or None, optional
        ``samples`` of :func:`coating_kernel` for a Scene (default
        :data:`DESIGN_SAMPLES`, 4096: pieces per analytic boundary, or rays per range-bin
        width of a mesh Scene; None: its own default); unused with a CoatingKernel. Hits
        take only the default or None (any other value is refused: their rays are
        traced).

    Returns
    -------
    ViewDesign
        The chosen views in the order added, each candidate's own information, and the
        parameters' σ from the chosen and from evenly spaced views.

    Raises
    ------
    ParameterError
        If ``budget`` is not an integer in [1, n_views], ``parts``, ``free`` or
        ``materials`` name no part or parameter of the kernel, ``photons_per_unit`` is
        invalid, Hits come with a ``samples`` other than the default or None, or
        :func:`coating_kernel` refuses the geometry.

    References
    ----------
    A. C. Atkinson, A. N. Donev and R. D. Tobias, *Optimum Experimental Designs, with SAS*,
    Oxford University Press (2007) (D-optimum designs).
    """
    budget = check_count("budget", budget)          # before a kernel is traced
    kernel = _kernel_of(geometry, ladar, samples)
    n_views = kernel.shape[0]
    if budget > n_views:
        raise ParameterError(f"budget must be at most the {n_views} candidate views; got "
                             f"{budget}")
    mats, params = _resolve_params(kernel, parts, free, None, materials)
    x = np.array([float(getattr(mats[p.part], p.name)) for p in params])
    m = kernel.predict(mats).ravel()
    scale = (1e5 / float(m.max()) if photons_per_unit is None else
             check_scale(photons_per_unit, float(m.max())))
    width = np.array([prm.high - prm.low if math.isfinite(prm.high - prm.low)
                      else max(abs(v), 1e-12) for prm, v in zip(params, x)])
    per_view = _per_view_fisher(kernel, (mats, params, x), m, scale, width)
    total = per_view.sum(axis=0)
    ridge = 1e-9 * float(np.trace(total)) / len(params) * np.eye(len(params))
    information = np.array([np.linalg.slogdet(F + ridge)[1] for F in per_view])
    chosen = _greedy(per_view, ridge, budget)
    uniform = np.round(np.arange(budget) * n_views / budget).astype(int)
    names = tuple(f"{kernel.parts[p.part]}.{p.name}" for p in params)
    return ViewDesign(np.array(chosen), np.asarray(kernel.angles_deg), information, names,
                      _stderr(per_view, chosen, ridge, width),
                      _stderr(per_view, uniform, ridge, width), uniform)


def _kernel_of(geometry, ladar, samples):
    """The geometry's coating kernel: a CoatingKernel itself, a Scene's at ``samples``,
    Hits' from their own rays (``samples`` only the default or None)."""
    if isinstance(geometry, CoatingKernel):
        return geometry
    if not isinstance(geometry, Hits):
        return coating_kernel(geometry, ladar, samples=samples)
    default = (isinstance(samples, Real) and not isinstance(samples, bool)
               and samples == DESIGN_SAMPLES)
    if samples is not None and not default:
        raise ParameterError(f"samples applies to a Scene; Hits carry their own rays: leave "
                             f"samples at its default or None; got {short(samples)}")
    return coating_kernel(geometry, ladar)


def _per_view_fisher(kernel, at, m, scale, width):
    """(n_views, n, n): each view's Fisher information of Poisson counts (model values
    ``m``) at ``at`` = (coatings, parameters, values), in units of each parameter's range
    ``width``."""
    mats, params, x = at
    n_views, n_bins = kernel.shape
    parts_ = sorted({q.part for q in params})
    base = {p: _table(mats[p]) for p in parts_}
    J = _jacobian({p: kernel.matrices[p] for p in parts_}, mats, params, x, base, scale,
                  m.size)
    V = np.maximum(m * scale, 1e-9 * float(m.max()) * scale)
    Js = J * width[None, :]                          # in units of each parameter's range
    return np.einsum("vbi,vbj->vij", (Js / V[:, None]).reshape(n_views, n_bins, -1),
                     Js.reshape(n_views, n_bins, -1))


def _greedy(per_view, ridge, budget):
    """Views added one at a time, each the one that most raises log det F."""
    chosen, F = [], ridge.copy()
    for _ in range(budget):
        best, gain = -1, -math.inf
        for v in range(per_view.shape[0]):
            if v in chosen:
                continue
            g = np.linalg.slogdet(F + per_view[v])[1]
            if g > gain:
                best, gain = v, g
        chosen.append(best)
        F = F + per_view[best]
    return chosen


def _stderr(per_view, idx, ridge, width):
    Fi = per_view[idx].sum(axis=0) + ridge
    return np.sqrt(np.abs(np.diag(np.linalg.pinv(Fi)))) * width
