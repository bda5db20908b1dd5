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
from ..errors import MeshladarWarning, ParameterError
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
    n, r = _TOL_START
    runs, last = [], []                    # every run's record; the last three values
    best = None                            # (estimate, sinogram, run index)
    order = 1.0
    spent = 0
    why = None
    for step in range(_TOL_STEPS + 1):
        if runs:
            # rays grow 2x per step in slice mode, 4x in 3-D: predict from the last run
            growth = 2.0 if sino.info["mode"] == "slice" else 4.0
            if spent + growth * runs[-1]["rays"] > max_rays:
                why = (f"the next run would cast about {growth * runs[-1]['rays']:.3g} rays, "
                       f"past the budget max_rays={max_rays:.3g} ({spent:.3g} cast so far); "
                       "raise max_rays or loosen tol")
                break
        mesh = scene.tessellate(n) if tessellate else scene
        t0 = time.perf_counter()
        with checked_by_caller():          # coarse runs undersample glints on purpose
            sino = simulate_mesh(mesh, ladar, normals=normals, rays_per_bin=r,
                                 footprint=footprint, **kwargs)
        spent += sino.info["rays"]
        runs.append({"segments": n if tessellate else None, "rays_per_bin": r,
                     "rays": sino.info["rays"], "seconds": time.perf_counter() - t0})
        last = (last + [sino.values])[-3:]
        if len(last) >= 2:
            est, order = _estimate(last, order)
            runs[-1]["error_estimate"] = est
            if best is not None and est >= best[0]:
                why = _stalled(est, best[0], footprint, normals)
                break
            best = (est, sino, len(runs) - 1, mesh)
            if est <= tol:
                break
        if tessellate:
            n *= 2
        r *= 2
    else:
        why = f"{_TOL_STEPS} refinements were not enough; loosen tol"
    if best is None:                       # a single run: nothing to estimate from
        best = (float("inf"), sino, len(runs) - 1, mesh)
    est, sino, k, _ = best
    _warn_kept(best, runs, why, tol, normals)
    info = dict(sino.info, tol=tol, error_estimate=est, convergence_order=order,
                max_rays=max_rays, rays_total=spent, stopped=why or "tol reached",
                chosen={"segments": runs[k]["segments"],
                        "rays_per_bin": runs[k]["rays_per_bin"], "normals": normals,
                        "footprint": footprint},
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
                      MeshladarWarning, stacklevel=5)


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
