"""Weigh and bin (the weigh stage): cached hits into a sinogram, F(θ)·δA⊥ per ray,
binned by range at a point or spread over its footprint (:func:`weigh`), and the mesh
model's sinogram of binned values with the record of how it was made (:func:`sinogram_of`).
It imports the :class:`Hits` record, never the tracer's entry points, so a material sweep
re-weighs cached hits without tracing. The per-hit weights live in :mod:`.hit_weights` and
the binning of one view in :mod:`.binning`; their names stay importable from here."""

from __future__ import annotations

import numpy as np

from .._validate import check_flag
from ..errors import ParameterError
from ..ladar import Ladar
from ..hits import Hits
from ..sinogram import Sinogram
from ..sensor import check_radiometry
from ..brdf import BRDF, check_brdf
# the binning and the per-hit weights (their own modules), re-exported here, where they
# always were
from .binning import bin_one
from .hit_weights import GRAZING_RECEIVER_COS, per_table_weight, scaled, weights

__all__ = ["weigh", "scaled", "per_table_weight"]


def weigh(hits: Hits, materials=None, *, footprint=False, bin_edges=None,
          radiometry="paper") -> Sinogram:
    """Turn hits into a sinogram: F(θ)·δA⊥ per ray, binned by range.

    Parameters
    ----------
    hits : Hits
        The first hits that ``meshladar.trace`` returns.
    materials : BRDF or list or tuple of BRDF, optional
        Replacement coatings, one per material index of the traced scene (default: the
        scene's; a single BRDF stands for a one-material scene). A material sweep
        re-weighs the same hits.
    footprint : bool
        Spread each ray over the range interval its footprint covers on the hit facet
        (default False). Monostatic hits of parallel rays only.
    bin_edges : array_like, optional
        Other range bins (default the ladar's), increasing, scene units.
    radiometry : {"paper", "power"}
        "paper" (default): Eq. 8, Σ F(θ_hit)·δA⊥; "power": received power, Σ F·cos θr·δA⊥
        (:mod:`meshladar.sensor`). The same hits serve both.

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins): per bin, the weights of the rays whose first hit
        lies in it, model "mesh"; ``info`` records the radiometry, mode, normals, footprint,
        ray spacing, sampling, seed, rays and back-face hits (and backend, units, and where
        they apply z0, receiver and sensor: :func:`sinogram_of`).

    Raises
    ------
    ParameterError
        When ``hits`` is not a Hits; ``footprint`` is not a bool; ``radiometry`` is not
        one of its choices; ``footprint`` meets bistatic hits or hits traced with a
        sensor; ``materials`` is not a BRDF, list or tuple, holds a non-BRDF, or does not
        give one coating per material index; ``bin_edges`` are not at least two strictly
        increasing edges; the hits' sensor needs ``radiometry="power"``
        (:func:`sinogram_of`).
    ModelError
        When a coating does not define ``projected``.

    References
    ----------
    Jin & Levine (2009), Eq. 8.

    Examples
    --------
    >>> import trimesh, meshladar as ml
    >>> ball = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3, radius=0.5),
    ...                           material=ml.materials.DARK_GRAY)
    >>> hits = ml.trace(ball, ml.Ladar.covering(ball, n_bins=64, angles_deg=[0.0, 90.0]))
    >>> gray = weigh(hits)                                    # the coating it was made with
    >>> glossy = weigh(hits, [ml.brdf.GGX(alpha=0.2)])        # another, on the same rays
    >>> gray.values.shape, glossy.values.shape
    ((2, 64), (2, 64))
    """
    mats, edges, power = _checked(hits, materials, footprint, bin_edges, radiometry)
    order = np.argsort(hits.view, kind="stable")
    bounds = np.searchsorted(hits.view[order], np.arange(hits.ladar.n_views + 1))
    vals = np.zeros((hits.ladar.n_views, len(edges) - 1))
    for i in range(hits.ladar.n_views):
        sel = order[bounds[i]:bounds[i + 1]]
        vals[i] = bin_one(hits.range[sel], hits.cos_theta[sel], hits.sin_theta[sel],
                          hits.material[sel], hits.spread[sel], mats, edges, hits.area,
                          footprint=footprint,
                          bi=None if hits.bistatic is None else hits.bistatic[sel],
                          factor=None if hits.weight_factor is None
                          else hits.weight_factor[sel],
                          curve=None if hits.curve is None else hits.curve[sel], power=power,
                          receive=None if hits.receive_factor is None
                          else hits.receive_factor[sel])
    return sinogram_of(vals, hits.ladar, edges, hits.info, normals=hits.normals,
                       footprint=footprint, rays=hits.rays, back=hits.back_face_hits,
                       radiometry=radiometry)


def _checked(hits, materials, footprint, bin_edges, radiometry):
    """(coatings, bin edges, power) of a :func:`weigh` call, after its arguments are
    checked: the hits, the flag, the radiometry, footprint binning against the hits, one
    coating per material index and the edges (the ladar's own checks)."""
    if not isinstance(hits, Hits):
        raise ParameterError(f"hits must be the Hits that meshladar.trace returns; got "
                             f"{type(hits).__name__}")
    check_flag("footprint", footprint)
    power = check_radiometry(radiometry)
    if footprint and hits.bistatic is not None:
        raise ParameterError("footprint binning is monostatic only; these hits are bistatic")
    if footprint and hits.info.get("traced_with") is not None:
        raise ParameterError("footprint binning is for parallel rays without a sensor; these "
                             "hits were traced with one")
    if isinstance(materials, BRDF):
        materials = [materials]                       # one coating for a one-material scene
    if materials is not None and not isinstance(materials, (list, tuple)):
        raise ParameterError(f"materials must be a list of coatings, one per material index; "
                             f"got {type(materials).__name__}")
    mats = hits.materials if materials is None else tuple(materials)
    for i, m in enumerate(mats):
        check_brdf(f"materials[{i}]", m)
    if len(mats) != len(hits.materials):
        raise ParameterError(f"materials must give {len(hits.materials)} coatings (one per "
                             f"material index); got {len(mats)}")
    if bin_edges is None:
        edges = hits.ladar.bin_edges
    else:
        edges = Ladar([0.0], bin_edges).bin_edges      # the ladar's own checks of edges
    return mats, edges, power


def sinogram_of(vals, ladar, edges, run, *, normals, footprint, rays, back, radiometry):
    """The mesh model's sinogram of binned ``vals`` (n_views, n_bins); its info says how it
    was made (``run``: mode, spacing, sampling, seed, receiver, sensor; normals, footprint,
    rays and back-face hits per view) and under which convention (radiometry).

    Parameters
    ----------
    vals : (n_views, n_bins) numpy.ndarray
        The binned profiles.
    ladar : meshladar.Ladar
        The views (their angles, and their view vectors when not all in the x-y plane).
    edges : (n_bins + 1,) numpy.ndarray
        The range bin edges.
    run : dict
        The run's parameters: ``"mode"``, ``"ray_spacing"``, ``"sampling"``, ``"seed"``,
        ``"z0"`` (slice mode), and optionally ``"backend"``, ``"receiver"`` and
        ``"sensor"``.
    normals : str
        The hits' normals, recorded.
    footprint : bool
        Whether footprint binning was used, recorded.
    rays : array_like of int
        Rays cast per view; their sum is recorded.
    back : array_like of int
        Back-face hits per view, recorded as a list.
    radiometry : {"paper", "power"}
        The convention of ``vals``, recorded.

    Returns
    -------
    Sinogram
        Model ``"mesh"``, with ``info`` holding the above and ``"units"``
        (``"length/sr (per unit height)"`` in slice mode, ``"area/sr"`` in 3-D, or
        ``"photoelectrons"``). With a sensor that counts photons, the values are
        multiplied by ``sensor.photoelectrons_per_unit()``.

    Raises
    ------
    ParameterError
        When the run's sensor has a non-zero extinction or counts photoelectrons and
        ``radiometry`` is not ``"power"``.
    """
    info = {"radiometry": radiometry, "mode": run["mode"], "normals": normals,
            "footprint": footprint, "ray_spacing": run["ray_spacing"],
            "sampling": run["sampling"], "seed": run["seed"], "rays": int(np.sum(rays)),
            "back_face_hits": np.asarray(back).tolist(), "backend": run.get("backend"),
            "units": "length/sr (per unit height)" if run["mode"] == "slice" else "area/sr"}
    if run["mode"] == "slice":
        info["z0"] = run["z0"]
    receiver = run.get("receiver")
    if receiver is not None:                 # bistatic: the receiver's direction(s)
        rows = np.unique(np.asarray(receiver, dtype=np.float64), axis=0)
        info["receiver"] = rows[0].tolist() if len(rows) == 1 else \
            np.asarray(receiver, dtype=np.float64).tolist()
    sensor = run.get("sensor")
    if sensor is not None:
        info["sensor"] = sensor.describe()
        if sensor.extinction > 0 and radiometry != "power":
            raise ParameterError(f"extinction ({sensor.extinction:g} per m) attenuates the "
                                 "received power: use radiometry='power' (Eq. 8 has no "
                                 "receiver; the paper convention ignores the atmosphere)")
        if sensor.counts_photons:
            if radiometry != "power":
                raise ParameterError("a sensor with pulse_energy and aperture_diameter counts "
                                     "photoelectrons of received power: use "
                                     "radiometry='power' (or drop them for Eq. 8)")
            vals = vals * sensor.photoelectrons_per_unit()
            info["units"] = "photoelectrons"
    return Sinogram(vals, angles_deg=ladar.angles_deg, bin_edges=edges, model="mesh",
                    view_vectors=None if ladar.planar else ladar.view_vectors, info=info)
