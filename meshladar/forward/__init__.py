"""``simulate``: one entry point for the forward models."""

from __future__ import annotations

import warnings

import numpy as np

from .._validate import check_choice
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..ladar import Ladar
from ..scene import Scene
from ..sinogram import Sinogram
from ..stream import check_jobs
from .analytic import simulate_analytic
from .orders import add_bounces, check_bounces
from .mesh import simulate_mesh, trace
from .options import MODELS, OPTIONS, options_of
from .pixel import simulate_pixel
from .refine import simulate_tol
from .resolved import resolve

__all__ = ["simulate", "MODELS", "OPTIONS", "trace", "simulate_mesh", "resolve"]


def simulate(scene, ladar, model="analytic", **options) -> Sinogram:
    """Range-resolved returns of ``scene`` seen by ``ladar``.

    Parameters
    ----------
    scene : Scene
        Analytic shapes (``Disk``, ``Ellipse``) or meshes (``Scene.from_mesh``).
    ladar : Ladar
        Views (``angles_deg`` about z, or ``view_vectors``) and range ``bin_edges``.
    model : {"analytic", "mesh", "pixel"}
        ``"analytic"``: exact profiles of disks and ellipses. ``"mesh"``: triangle meshes
        ray-cast with Embree, a 3-D target unless tessellated from analytic shapes, with
        the options of :func:`meshladar.forward.mesh.simulate_mesh` (mode, normals, rays,
        footprint, receiver, backend, ``sensor``: a standoff, beam and link budget) and
        ``tol``. ``"pixel"``: the paper's method, a rasterised surface traced with Siddon
        rays (:func:`meshladar.forward.pixel.simulate_pixel`).
    radiometry : {"paper", "power"}, every model
        "paper" (default): the paper's Eq. 8, bins of ∫ F(θ) cos θ dA; "power": the power a
        receiver collects, ∫ F cos θ_i cos θ_r dA (:mod:`meshladar.sensor`).
    tol : float in (0, 1), optional, mesh model only
        A relative L2 accuracy instead of a ray density: rays per bin (and segments) double
        until a refinement check estimates the error at most ``tol``, within ``max_rays``;
        ``info`` records the choice and every run (:mod:`meshladar.forward.refine`).
    jobs : int, optional
        Workers for chunks of views. The mesh model's are threads sharing one Embree
        scene; by default 1 below :data:`meshladar.stream.THREADS_FROM` rays in all, else
        one per core (at most one per chunk of views; a single view splits its rows over
        them). The analytic and pixel models' are processes; by default 1 (no pool).
    executor : concurrent.futures.Executor, optional
        Any executor to run the chunks on (:func:`meshladar.stream.dask_executor`'s for a
        Dask cluster); overrides ``jobs``.
    progress : bool
        A progress bar over the views, on a terminal only.
    run_dir : path, optional
        A run folder: each finished chunk of views is saved there and the same job run
        again computes only what is missing (:mod:`meshladar.runs`).
    **options
        The chosen model's own options; an option another model takes is an error.

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins), float64: bin integrals of F(θ) cos θ dA (Eq. 8) or
        of received power, with ``angles_deg`` (or ``view_vectors``), ``bin_edges``,
        ``model``, and ``info`` (the convention and options the run used).

    Raises
    ------
    ParameterError
        If ``scene`` or ``ladar`` is of the wrong type, ``model`` not one of
        :data:`MODELS`, an option one the model does not take, ``jobs`` invalid,
        ``run_dir`` combined with ``tol``, or a mesh scene or views off the x-y plane given
        to the analytic or pixel model; and whatever the chosen model refuses.

    Warns
    -----
    MeshladarWarning
        When the analytic or pixel model's sinogram is all zeros (the bins miss the
        scene), naming the scene's range span and the bins'.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the ``"paper"`` radiometry).

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> scene = ml.Scene([ml.Disk((0.0, 0.0), 0.8, ml.materials.DARK_GRAY)])
    >>> ladar = ml.Ladar(angles_deg=np.arange(0.0, 360.0), bin_edges=np.linspace(-1, 1, 257))
    >>> ml.simulate(scene, ladar).values.shape
    (360, 256)
    """
    _check_call(scene, ladar, model, options)
    return _RUNNERS[model](scene, ladar, options)


def _check_call(scene, ladar, model, options):
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    if not isinstance(ladar, Ladar):
        raise ParameterError(f"ladar must be a meshladar.Ladar; got {type(ladar).__name__}")
    check_choice("model", model, MODELS)
    takes = options_of(model)              # the options table: meshladar.forward.options
    unknown = sorted(set(options) - set(takes))
    if unknown:
        raise ParameterError(f"model {model!r} takes options {takes}; got {unknown[0]!r}")
    check_jobs(options.get("jobs"))          # the stream's, checked before any plan's warning


def _run_mesh(scene, ladar, options):
    """The mesh model: one run, or the accuracy knob's refinement (``tol``); then the
    orders of bounces beyond the first (:mod:`meshladar.forward.bounces`)."""
    bounces, samples = check_bounces(scene, options.pop("bounces", None),
                                     options.pop("bounce_samples", None), options)
    tol = options.get("tol")
    sino = _single_bounce(scene, ladar, options)
    return add_bounces(scene, ladar, sino, bounces, samples, tol=tol,
                       seed=options.get("seed"), sensor=options.get("sensor"))


def _single_bounce(scene, ladar, options):
    """One run, or the accuracy knob's refinement (``tol``)."""
    tol, max_rays = options.pop("tol", None), options.pop("max_rays", None)
    if tol is not None:
        if options.get("run_dir") is not None:
            raise ParameterError("run_dir and tol do not combine: the knob runs several "
                                 "jobs")
        normals, footprint = options.pop("normals", None), options.pop("footprint", None)
        options.pop("run_dir", None)
        options.setdefault("ray_spacing", None)
        options.setdefault("rays_per_bin", None)
        return simulate_tol(scene, ladar, tol, normals, footprint, max_rays, options)
    if max_rays is not None:
        raise ParameterError("max_rays is the budget of the tol knob; give tol too")
    return simulate_mesh(scene, ladar, **options)


def _planar(simulate_model, model):
    """A 2-D model's runner: analytic shapes and views about z only; says so when the
    sinogram is all zeros."""
    def run(scene, ladar, options):
        if not scene.shapes:
            raise ParameterError(f"model {model!r} needs analytic shapes (Disk, Ellipse); "
                                 "this scene is a mesh: use model='mesh'")
        if not ladar.planar:
            raise ParameterError(f"model {model!r} needs views about the z axis; the ladar "
                                 "has view vectors off the x-y plane")
        sino = simulate_model(scene, ladar, **options)
        if not np.any(sino.values):
            lo, hi = scene.range_span(ladar.view_vectors)
            warnings.warn(f"the sinogram is all zeros: the scene spans ranges [{lo:.6g}, "
                          f"{hi:.6g}] over these views (its lit side the nearer half), the "
                          f"bins cover [{ladar.bin_edges[0]:.6g}, "
                          f"{ladar.bin_edges[-1]:.6g}]", MeshladarWarning, stacklevel=user_stacklevel())
        return sino

    return run


#: The forward models' runners by name (a new model registers here and in MODELS).
_RUNNERS = {"analytic": _planar(simulate_analytic, "analytic"),
            "pixel": _planar(simulate_pixel, "pixel"), "mesh": _run_mesh}
