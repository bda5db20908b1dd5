"""``simulate``: one entry point for the forward models (DESIGN.md's pipeline)."""

from __future__ import annotations

import numpy as np

from ._validate import check_choice
from .errors import ParameterError
from .ladar import Ladar
from .scene import Scene
from .sinogram import Sinogram

__all__ = ["simulate", "MODELS"]

#: The forward models available in this version.
MODELS = ("analytic", "mesh", "pixel")

_OPTIONS = {"analytic": ("progress",), "pixel": ("pixel_size", "ray_spacing", "progress"),
            "mesh": ("mode", "normals", "back_faces", "z0", "ray_spacing", "rays_per_bin",
                     "footprint", "sampling", "seed", "receiver", "tol", "max_rays", "jobs",
                     "executor", "progress", "run_dir")}


def simulate(scene, ladar, model="analytic", **options) -> Sinogram:
    """Range-resolved returns of ``scene`` seen by ``ladar``.

    Parameters
    ----------
    scene : Scene
    ladar : Ladar
    model : str
        ``"analytic"``: exact profiles of disks and ellipses (no faceting, no sampling;
        option ``progress``).
        ``"mesh"``: triangle meshes ray-cast with Embree (options in
        :func:`meshladar.raytrace.simulate_mesh`: mode, normals, back_faces, z0, ray_spacing,
        rays_per_bin, footprint, sampling, seed, receiver, tol, max_rays, jobs, executor,
        progress, run_dir). A mesh is a 3-D target (``mode="3d"``) unless it was
        tessellated from the analytic shapes.
        ``"pixel"``: the paper's method, a rasterised surface traced with Siddon rays
        (options ``pixel_size``, ``ray_spacing``, ``progress``; see
        :func:`meshladar.pixel.simulate_pixel`).
    **options
        Options of the chosen model; an option another model takes is an error.

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins) bin integrals of F(θ) cos θ dA (paper Eq. 8).
    """
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    if not isinstance(ladar, Ladar):
        raise ParameterError(f"ladar must be a meshladar.Ladar; got {type(ladar).__name__}")
    check_choice("model", model, MODELS)
    unknown = sorted(set(options) - set(_OPTIONS[model]))
    if unknown:
        raise ParameterError(f"model {model!r} takes options {_OPTIONS[model]}; got "
                             f"{unknown[0]!r}")
    if model == "mesh":
        from .raytrace import simulate_mesh

        return simulate_mesh(scene, ladar, **options)
    if not scene.shapes:
        raise ParameterError(f"model {model!r} needs analytic shapes (Disk, Ellipse); this "
                             "scene is a mesh: use model='mesh'")
    if not ladar.planar:
        raise ParameterError(f"model {model!r} needs views about the z axis; the ladar has "
                             "view vectors off the x-y plane")
    if model == "pixel":
        from .pixel import simulate_pixel

        sino = simulate_pixel(scene, ladar, **options)
    else:
        from .analytic import simulate_analytic

        sino = simulate_analytic(scene, ladar, **options)
    if not np.any(sino.values):
        import warnings

        from .errors import MeshladarWarning

        lo, hi = scene.range_span(ladar.view_vectors)
        warnings.warn(f"the sinogram is all zeros: the scene spans ranges [{lo:.6g}, "
                      f"{hi:.6g}] over these views (its lit side the nearer half), the bins "
                      f"cover [{ladar.bin_edges[0]:.6g}, {ladar.bin_edges[-1]:.6g}]",
                      MeshladarWarning, stacklevel=2)
    return sino
