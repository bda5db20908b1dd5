"""The accuracy knob (``simulate(..., model="mesh", tol=...)``): refine a model's run until
its estimated relative L2 error meets ``tol``.

It sits above the mesh model's entry point (:func:`meshladar.forward.mesh.simulate_mesh`), which
it calls once per refinement, and below :func:`meshladar.simulate`, which dispatches ``tol``
here; it knows nothing of rays or Embree.
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from .._validate import check_real
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from .mesh import simulate_mesh
from .sampling import checked_by_caller, warn_unresolved_lobes
from ..sinogram import Sinogram
from ..precision import TINY

__all__ = ["simulate_tol", "TOL_MAX_RAYS"]


#: The accuracy knob starts here (segments for scenes it tessellates, rays per bin) and
#: doubles both until the error estimate meets tol, at most _TOL_STEPS times.
_TOL_START = (256, 1.0)
_TOL_STEPS = 6
#: Bounds on the convergence order estimated from three successive runs.
_ORDER_BOUNDS = (0.3, 2.0)
#: Default budget of rays the knob may cast over all its runs (about 2–5 minutes here).
TOL_MAX_RAYS = 2e9


def simulate_tol(scene, ladar, tol, normals, footprint, max_rays, kwargs):
    """The accuracy knob: refine until the estimated relative L2 error is at most tol.

    Each step doubles the rays per bin (and, for a scene meshladar tessellates itself, the
    segments). The error of the finer run S₁ is estimated from its difference to the
    coarser S₀, d = ‖S₁ − S₀‖/‖S₁‖, as d·2^−p/(1 − 2^−p) with p the convergence order
    measured from the last three runs (p = 1 until there are three), so that slowly
    converging cases are not accepted early.

    It stops early, keeping the run with the smallest estimate, when an estimate fails to
    fall below the best so far (refinement no longer converges: noise or a singular
    feature dominates) or when the next run would take the rays cast past ``max_rays``;
    both warn with the estimate reached and what to change.

    The first run has 1 ray per bin width (and 256 segments per shape); there are at most
    6 refinements (7 runs), each doubling both. The order p is clipped to [0.3, 2]. The
    next run's rays are predicted as 2× the last run's in slice mode, 4× in 3-D. Only the
    run kept is checked for undersampled glints (:func:`warn_unresolved_lobes`); the
    coarser runs are not.

    Parameters
    ----------
    scene : Scene
        A mesh scene, or a scene of analytic shapes, which is tessellated afresh for each
        run.
    ladar : Ladar
        Views and range bins.
    tol : float
        The relative L2 error wanted, in (0, 1).
    normals : {"flat", "smooth", "exact"} or None
        Shading normals; None: ``"exact"`` for a scene tessellated here, ``"smooth"`` for a
        mesh.
    footprint : bool or None
        Footprint binning; None: True unless ``kwargs`` gives a ``receiver``.
    max_rays : float or None
        Budget of rays over all runs, ≥ 1; None: :data:`TOL_MAX_RAYS` (2e9).
    kwargs : dict
        The other options of :func:`meshladar.forward.mesh.simulate_mesh`; it must hold
        ``"ray_spacing"`` and ``"rays_per_bin"`` (both None: the knob picks the density),
        which are popped from it (the dict is changed).

    Returns
    -------
    Sinogram
        The kept run's values (model ``"mesh"``) with ``info`` extended by ``tol``,
        ``error_estimate`` (inf when only one run was made), ``convergence_order``,
        ``max_rays``, ``rays_total`` (over all runs), ``stopped`` (``"tol reached"`` or
        why not), ``chosen`` (the kept run's ``segments``, ``rays_per_bin``, ``normals``,
        ``footprint``) and ``refinement`` (one record per run: segments, rays_per_bin,
        rays, seconds, and error_estimate from the second run on).

    Raises
    ------
    ParameterError
        If ``tol`` is not in (0, 1), ``max_rays`` is not a finite real ≥ 1, or
        ``ray_spacing`` or ``rays_per_bin`` is given; and whatever ``simulate_mesh``
        refuses.

    Warns
    -----
    MeshladarWarning
        When ``tol`` is not reached: the reason, and the estimate of the run returned.
    LobeSamplingWarning
        When the kept run's rays undersample a coating's glint.
    """
    knob = _Knob.checked(scene, tol, normals, footprint, max_rays, kwargs)
    while knob.another_run():
        mesh = scene.tessellate(knob.segments) if knob.tessellate else scene
        t0 = time.perf_counter()
        with checked_by_caller():          # coarse runs undersample glints on purpose
            sino = simulate_mesh(mesh, ladar, normals=knob.normals, footprint=knob.footprint,
                                 rays_per_bin=knob.rays_per_bin, **kwargs)
        knob.record(sino, mesh, time.perf_counter() - t0)
    _warn_kept(knob.kept(), knob.runs, knob.why, knob.tol, knob.normals)
    return knob.result(ladar)


class _Knob:
    """The knob's bookkeeping over its runs: the checked settings, the next run's density,
    every run's record, the best run so far and why refinement stopped (None: tol reached).

    :func:`simulate_tol` asks :meth:`another_run`, makes the run itself (so that the mesh
    model's warnings keep their stack level) and hands it to :meth:`record`."""

    def __init__(self, tol, max_rays, tessellate, normals, footprint):
        self.tol, self.max_rays, self.tessellate = tol, max_rays, tessellate
        self.normals, self.footprint = normals, footprint
        self.segments, self.rays_per_bin = _TOL_START
        self.runs, self.last = [], []      # every run's record; the last three values
        self.best = None                   # (estimate, sinogram, run index, mesh)
        self.order = 1.0
        self.spent = 0
        self.why = None
        self.done = False
        self.sino = self.mesh = None       # the latest run

    @classmethod
    def checked(cls, scene, tol, normals, footprint, max_rays, kwargs):
        """The knob of a run, its arguments checked and its defaults chosen; pops
        ``ray_spacing`` and ``rays_per_bin`` from ``kwargs`` (refusing either given)."""
        tol = check_real("tol", tol, low=0.0, high=1.0, low_open=True, high_open=True)
        max_rays = check_real("max_rays", TOL_MAX_RAYS if max_rays is None else max_rays,
                              low=1.0)
        if kwargs.pop("ray_spacing") is not None or kwargs.pop("rays_per_bin") is not None:
            raise ParameterError("tol chooses the ray density itself: drop ray_spacing and "
                                 "rays_per_bin, or drop tol")
        tessellate = not scene.is_mesh
        if normals is None:
            normals = "exact" if tessellate else "smooth"
        if footprint is None:
            footprint = kwargs.get("receiver") is None
        return cls(tol, max_rays, tessellate, normals, footprint)

    def another_run(self):
        """Whether to make another run: not once tol is met or refinement stalled, nor
        after the last refinement, nor when the next run would pass the ray budget (the
        last two say why)."""
        if self.done:
            return False
        if len(self.runs) > _TOL_STEPS:
            self.why = f"{_TOL_STEPS} refinements were not enough; loosen tol"
            return False
        if self.runs:
            # rays grow 2x per step in slice mode, 4x in 3-D: predict from the last run
            growth = 2.0 if self.sino.info["mode"] == "slice" else 4.0
            more = growth * self.runs[-1]["rays"]
            if self.spent + more > self.max_rays:
                self.why = (f"the next run would cast about {more:.3g} rays, past the budget "
                            f"max_rays={self.max_rays:.3g} ({self.spent:.3g} cast so far); "
                            "raise max_rays or loosen tol")
                return False
        return True

    def record(self, sino, mesh, seconds):
        """Take a run in: its record, its error estimate (from the second run on), the best
        run so far; stop when tol is met or the estimate stops falling, else refine."""
        self.sino, self.mesh = sino, mesh
        self.spent += sino.info["rays"]
        self.runs.append({"segments": self.segments if self.tessellate else None,
                          "rays_per_bin": self.rays_per_bin, "rays": sino.info["rays"],
                          "seconds": seconds})
        self.last = (self.last + [sino.values])[-3:]
        if len(self.last) >= 2:
            est, self.order = _estimate(self.last, self.order)
            self.runs[-1]["error_estimate"] = est
            if self.best is not None and est >= self.best[0]:
                self.why = _stalled(est, self.best[0], self.footprint, self.normals)
                self.done = True
                return
            self.best = (est, sino, len(self.runs) - 1, mesh)
            if est <= self.tol:
                self.done = True
                return
        if self.tessellate:
            self.segments *= 2
        self.rays_per_bin *= 2

    def kept(self):
        """(estimate, sinogram, run index, mesh) of the run kept: the best estimated, or
        the only run (estimate inf: nothing to estimate from)."""
        if self.best is None:
            self.best = (float("inf"), self.sino, len(self.runs) - 1, self.mesh)
        return self.best

    def result(self, ladar):
        """The kept run's sinogram, its ``info`` extended by how the knob got there."""
        est, sino, k, _ = self.kept()
        runs = self.runs
        info = dict(sino.info, tol=self.tol, error_estimate=est, convergence_order=self.order,
                    max_rays=self.max_rays, rays_total=self.spent,
                    stopped=self.why or "tol reached",
                    chosen={"segments": runs[k]["segments"],
                            "rays_per_bin": runs[k]["rays_per_bin"], "normals": self.normals,
                            "footprint": self.footprint},
                    refinement=runs)
        return Sinogram(sino.values, angles_deg=sino.angles_deg, bin_edges=sino.bin_edges,
                        model="mesh", info=info,
                        view_vectors=None if ladar.planar else ladar.view_vectors)


def _warn_kept(best, runs, why, tol, normals):
    """The warnings about the run kept: tol not reached (why), and a glint its rays leave
    undersampled (the coarse runs before it are not checked)."""
    est, sino, k, mesh = best
    warn_unresolved_lobes(mesh, mesh.materials, spacing=sino.info["ray_spacing"],
                          normals=normals, mode=sino.info["mode"],
                          sampling=sino.info.get("sampling") or "stratified")
    if why is not None:
        segments = runs[k]["segments"]
        warnings.warn(f"tol={tol:g} not reached: {why}; returning the run with estimated "
                      f"error {est:.2g} ({runs[k]['rays_per_bin']:g} rays per bin"
                      + (f", {segments} segments" if segments is not None else "") + ")",
                      MeshladarWarning, stacklevel=user_stacklevel())


def _estimate(last, order):
    """The latest run's estimated relative error from the last two (or three) runs'
    values, and the convergence order measured from three: (estimate, order)."""
    d1 = np.linalg.norm(last[-1] - last[-2])
    if len(last) >= 3:
        d0 = np.linalg.norm(last[-2] - last[-3])
        if d1 > 0 and d0 > 0:
            order = float(np.clip(math.log2(d0 / d1), *_ORDER_BOUNDS))
    factor = 2.0 ** -order / (1.0 - 2.0 ** -order)
    return d1 / max(np.linalg.norm(last[-1]), TINY) * factor, order


def _stalled(est, best, footprint, normals):
    """Why refinement stopped converging, and what to try."""
    tips = [t for t, use in (("footprint=True", not footprint),
                             ("smooth or exact normals", normals == "flat"))
            if use] + ["a looser tol"]
    return (f"refinement stopped converging (estimate {est:.2g} after "
            f"{best:.2g}): sampling noise or a singular feature dominates "
            "(a glint spot or silhouette narrower than the ray spacing); try "
            + ", ".join(tips))
