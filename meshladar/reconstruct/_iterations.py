"""The iterations of the solvers of :mod:`meshladar.reconstruct.iterative` on a problem set
up by ``_problem``: SIRT's scaled steps, SART's ordered subsets, CGLS's conjugate gradients
and FISTA with the TV proximal map; each records its run and returns the result image.

The run's bookkeeping is shared: :class:`_Progress` keeps the residual history, the progress
bar and the stopping rule; residuals are weighted (‖W^½ r‖) and relative to the weighted
‖b‖. Every loop runs on the problem's data at unit scale (b divided by a power of two,
``_problem``): the image is multiplied back at the end (:func:`_image`), so a run on data
scaled by 2^k gives the image scaled by 2^k and the same residuals, bit for bit.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._validate import check_count
from ..errors import ParameterError
from ..images import Image
from ..stream import Progress
from ._tv import gradient, tv_prox
from .fbp2d import quiet_fbp
from .operators import build, projector_name


class _Progress:
    """An iterative run's bookkeeping: the residual history, the progress bar and the
    stopping rule (stop when a step lowers the tracked value by less than ``tol``
    relatively)."""

    def __init__(self, n_iter, tol, progress):
        self.values, self.tol, self.stopped = [], tol, "n_iter"
        self.bar = Progress(n_iter, "iterations") if progress else None

    def step(self, value, tracked=None):
        """Record a step; True when the run should stop."""
        self.values.append(value)
        tracked = self.values if tracked is None else tracked
        if self.bar is not None:
            self.bar.update(1)
        if (self.tol is not None and len(tracked) > 1
                and abs(tracked[-2] - tracked[-1]) < self.tol * tracked[-2]):
            self.stopped = "tol"
            return True
        return False

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _image(x, pr, info):
    """The result: ``x`` (at the data's unit scale) times the problem's scale, on the image
    grid (size, extent, center) the caller gave; refused beyond float64's range."""
    _, extent, center = pr.image
    with np.errstate(over="ignore"):
        values = x * pr.scale
    if not np.all(np.isfinite(values)):
        raise ParameterError(f"sino: values of order {pr.scale:.3g} give an image beyond "
                             "float64's range (1.8e308); rescale the values")
    return Image(values, extent, tuple(float(c) for c in center), info=info)


def _norm(r, W):
    return float(np.sqrt(np.sum(W * r * r)))


def _projector_name(projector, sino):                   # the pair used, or the operator's type
    return (projector_name(projector, sino.bin_edges) if isinstance(projector, str)
            else type(projector).__name__)


def _scalings(A, W, M, relax=1.0):
    """SIRT's scalings of the projector A: R, the inverse row sums over the allowed pixels M
    times the weights W, and C, ``relax`` over the weighted column sums (0 where a sum is
    0)."""
    rows = A @ (M * 1.0)                                   # row sums over allowed pixels
    R = np.where(rows > 0, 1.0 / np.where(rows > 0, rows, 1.0), 0.0) * W
    cols = (A.T @ W) * M                                   # column sums, weighted
    C = np.where(cols > 0, relax / np.where(cols > 0, cols, 1.0), 0.0)
    return R, C


def _sirt(sino, pr, run, nonneg):
    """SIRT from ``pr.x``: x ← x + C Aᵀ R (b − A x), then x ≥ 0 (``nonneg``) and the mask."""
    A, b, W, M, x = pr.A, pr.b, pr.W, pr.M, pr.x
    R, C = _scalings(A, W, M)
    bnorm = _norm(b, W) or 1.0
    track = _Progress(run.n_iter, run.tol, run.progress)
    r = b - A @ x
    for _ in range(run.n_iter):
        x = x + C * (A.T @ (R * r))
        x *= M
        if nonneg:
            np.maximum(x, 0.0, out=x)
        r = b - A @ x
        if track.step(_norm(r, W) / bnorm):
            break
    track.close()
    info = {"method": "sirt", "iterations": len(track.values), "residuals": track.values,
            "stopped": track.stopped, "nonneg": bool(nonneg),
            "projector": _projector_name(run.projector, sino), "rays_per_bin": run.rays_per_bin,
            "radiometry": sino.radiometry}
    return _image(x, pr, info)


def _groups(sino, pr, n_sub, projector, relax, rays_per_bin):
    """SART's ``n_sub`` groups of views, group k the views k, k + n_sub, ...: for each, its
    views' indices, their projector (``projector``, a name) and SIRT's scalings R and C
    (C relaxed by ``relax``)."""
    b, W, M = pr.b, pr.W, pr.M
    groups = []
    for k in range(n_sub):
        idx = np.arange(k, b.shape[0], n_sub)
        part = dataclasses.replace(sino, values=b[idx], angles_deg=sino.angles_deg[idx],
                                   view_vectors=sino.view_vectors[idx])
        As = build(projector, pr.grid, part, rays_per_bin)
        R, C = _scalings(As, W[idx], M, relax)
        groups.append((idx, As, R, C))
    return groups


def _sart(sino, pr, run, subsets, relax, nonneg):
    """SART in ``subsets`` ordered groups of views (None: one per 36 views, checked here),
    each sweep taking SIRT's step on each group in turn; ``pr`` built without a projector."""
    projector = projector_name(run.projector, sino.bin_edges)
    b, W, M, x = pr.b, pr.W, pr.M, pr.x
    n_views = b.shape[0]
    n_sub = max(1, n_views // 36) if subsets is None else check_count("subsets", subsets)
    if n_sub > n_views:
        raise ParameterError(f"subsets must be at most the number of views ({n_views}); "
                             f"got {n_sub}")
    groups = _groups(sino, pr, n_sub, projector, relax, run.rays_per_bin)
    bnorm = _norm(b, W) or 1.0
    track = _Progress(run.n_iter, run.tol, run.progress)
    for _ in range(run.n_iter):
        gathered = 0.0
        for idx, As, R, C in groups:
            r = b[idx] - As @ x
            gathered += float(np.sum(W[idx] * r * r))
            x = x + C * (As.T @ (R * r))
            x *= M
            if nonneg:
                np.maximum(x, 0.0, out=x)
        if track.step(math.sqrt(gathered) / bnorm):
            break
    track.close()
    info = {"method": "sart", "subsets": n_sub, "relax": relax,
            "iterations": len(track.values), "residuals": track.values,
            "stopped": track.stopped, "nonneg": bool(nonneg), "projector": projector,
            "rays_per_bin": run.rays_per_bin, "radiometry": sino.radiometry}
    return _image(x, pr, info)


def _cgls(sino, pr, run):
    """CGLS from ``pr.x``: conjugate gradients on the normal equations over the masked
    pixels; stops "converged" when the masked gradient is 0 or the search direction
    projects to 0."""
    A, b, W, M, x = pr.A, pr.b, pr.W, pr.M, pr.x
    r = b - A @ x
    s = M * (A.T @ (W * r))
    p = s.copy()
    gamma = float(np.sum(s * s))
    bnorm = _norm(b, W) or 1.0
    track = _Progress(run.n_iter, run.tol, run.progress)
    for _ in range(run.n_iter):
        if gamma == 0:
            track.stopped = "converged"
            break
        q = A @ p
        qq = float(np.sum(W * q * q))
        if not qq > 0:               # the rays carry nothing back (pixels far below the bins)
            track.stopped = "converged"
            break
        alpha = gamma / qq
        x = x + alpha * p
        r = r - alpha * q
        s = M * (A.T @ (W * r))
        gamma_new = float(np.sum(s * s))
        p = s + (gamma_new / gamma) * p
        gamma = gamma_new
        if track.step(_norm(r, W) / bnorm):
            break
    track.close()
    info = {"method": "cgls", "iterations": len(track.values), "residuals": track.values,
            "stopped": track.stopped, "projector": _projector_name(run.projector, sino),
            "rays_per_bin": run.rays_per_bin, "radiometry": sino.radiometry}
    return _image(x, pr, info)


def _lipschitz(pr):
    """L = ‖W^½ A‖² over the masked pixels, by 15 power iterations on M Aᵀ W A M from a
    seeded random start (``numpy.random.default_rng(0)``: runs repeat exactly)."""
    A, W, M = pr.A, pr.W, pr.M
    rng = np.random.default_rng(0)
    v = rng.random(pr.grid.shape) * M
    for _ in range(15):                                    # power iteration: ‖W^½ A‖²
        v = M * (A.T @ (W * (A @ v)))
        L = float(np.linalg.norm(v))
        v /= L if L > 0 else 1.0
    return L


def _fista(sino, pr, run, tv, nonneg):
    """FISTA from ``pr.x`` on ½‖W^½ (A x − b)‖² + λ TV(x), λ = ``tv`` · L · (the 99th
    percentile of |FBP image|), each step a gradient step of 1/L and the TV proximal map
    (warm-started from the previous step's dual); ``tol`` tracks the objective."""
    A, b, W, M, x = pr.A, pr.b, pr.W, pr.M, pr.x
    L = _lipschitz(pr)
    size, extent, center = pr.image
    first = quiet_fbp(pr.sino, size, extent, center=center)     # at the data's unit scale
    level = float(np.percentile(np.abs(first), 99)) or 1.0
    lam = tv * L * level
    bnorm = _norm(b, W) or 1.0
    y, t = x.copy(), 1.0
    dual = None
    objective = []
    track = _Progress(run.n_iter, run.tol, run.progress)
    for _ in range(run.n_iter):
        g = M * (A.T @ (W * (A @ y - b)))
        x_new, dual = tv_prox(y - g / L, lam / L, nonneg, M, dual=dual)
        t_new = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * t * t))
        y = x_new + (t - 1.0) / t_new * (x_new - x)
        x, t = x_new, t_new
        r = A @ x - b
        gx, gy = gradient(x)
        objective.append((0.5 * float(np.sum(W * r * r))
                          + lam * float(np.sum(np.hypot(gx, gy)))) / (0.5 * bnorm * bnorm))
        if track.step(_norm(r, W) / bnorm, objective):
            break
    track.close()
    info = {"method": "tv_fista", "tv": tv, "lambda": lam * pr.scale, "lipschitz": L,
            "iterations": len(track.values), "residuals": track.values, "objective": objective,
            "stopped": track.stopped, "nonneg": bool(nonneg),
            "projector": _projector_name(run.projector, sino), "radiometry": sino.radiometry}
    return _image(x, pr, info)
