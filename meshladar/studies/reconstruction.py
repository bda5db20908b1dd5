"""The reconstruction study (``meshladar study reconstruction``): for the paper's phantoms
and coatings and view spacings of 1°, 5°, 10° and 20°, each reconstruction method's image
error against the ideal reconstruction, the paper's metrics, and wall time.

The ideal reconstruction of a scene is the image of its surface seen without BRDF effects
or shadowing: each shape alone, Lambertian, reconstructed by FBP from 1° views, summed.
Two image measures, both scale-free (a coating changes a reconstruction's level, not what
it should look like):

* ``error`` (surface error): along every true boundary, the line density (the image
  integrated across a band of ±2 bins) divided by the ideal's; its spread (std / mean)
  over all the surfaces. 0 when every part of every surface is rendered in proportion to
  the ideal; edge darkening, shadow gaps and a glint outshining a diffuse surface raise it.
* ``clutter``: the share of the image's absolute integral inside the scene's bounding
  circle that lies off the surfaces' bands (streaks, halos, negative pedestals).

Metrics: edge darkening for a lone disk, gray-disk visibility for the pair
(:mod:`meshladar.studies.paper`).
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from dataclasses import fields

import numpy as np

from .. import materials
from .. import phantoms as _specs
from .._validate import check_choice, check_real, short
from ..brdf import Lambertian, SandfordRobertson
from ..reconstruct.compensation import compensate
from ..errors import MeshladarWarning, ParameterError
from ..forward import simulate
from ..reconstruct.iterative import cgls, glint_weights, sart, sirt, tv_fista
from ..ladar import Ladar
from ..noise import draw_noise, Noise
from ..reconstruct import Image, clip_radiance, fbp, log_radiance
from ..scene import Scene
from . import paper

__all__ = ["METHODS", "SPACINGS", "run", "report"]

#: Reconstruction methods compared (FBP and its paper preprocessings, iterative solvers).
METHODS = ("fbp", "fbp_log", "fbp_clip", "sirt", "sirt_glint", "sart", "cgls", "tv",
           "compensated")
#: View spacings in degrees.
SPACINGS = (1.0, 5.0, 10.0, 20.0)
#: Boundary samples per judged arc (720 per boundary: 4° arcs).
_ARC = 8
#: Settings: (image size, range bins across the disk's diameter, iterations).
_SETTINGS = {"quick": (128, 128, 40), "full": (256, 256, 100)}


def _phantoms():
    return {"disk_b0.99": _specs.scene("disk", paper._diffuse(0.99)),
            "pair_gray_al": paper._pair(materials.DARK_GRAY, materials.ALUMINUM)}


def _reconstruct(method, sino, size, n_iter, scene=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshladarWarning)        # FBP's few-views warning
        if method == "fbp":
            return fbp(sino, size=size, extent=1.0)
        if method == "fbp_log":
            return fbp(log_radiance(sino), size=size, extent=1.0)
        if method == "fbp_clip":
            return fbp(clip_radiance(sino), size=size, extent=1.0)
    if method == "compensated":
        return _compensated(sino, size, n_iter, scene)
    return _iterate(method, sino, size, n_iter)


def _compensated(sino, size, n_iter, scene):
    """BRDF compensation with the scene's coatings known: each surface pixel takes the
    coating of the nearest boundary. Where a coating glints (an SR glint narrower than
    0.05 rad: narrower than the normals' accuracy, so it cannot be compensated), the bins
    brighter than the clip level are dropped and the coatings' diffuse lobes compensated
    (measured at 1° on the gray/aluminium pair: surface error 0.68 and gray-disk
    visibility 2.3, against 4.0 and 0.07 compensating the whole BRDF)."""
    c = -1.0 + (np.arange(size) + 0.5) * (2.0 / size)
    X, Y = np.meshgrid(c, c)
    dist = [np.abs(np.hypot(X - sh.center[0], Y - sh.center[1]) - sh.radius)
            for sh in scene.shapes]
    labels = np.argmin(dist, axis=0)
    mats = [sh.material for sh in scene.shapes]
    glints = any(isinstance(m, SandfordRobertson) and m.has_specular and m.e < 0.05
                 for m in mats)
    if glints:
        mats = [dataclasses.replace(m, lobes="diffuse") if isinstance(m, SandfordRobertson)
                and m.has_diffuse else m for m in mats]
    return compensate(sino, mats, labels=labels, size=size, extent=1.0, method="sirt",
                      n_iter=n_iter, weights=glint_weights(sino) if glints else None)


def _iterate(method, sino, size, n_iter):
    if method == "sart":             # ten groups: a sweep moves about as far as ten SIRT steps
        return sart(sino, size=size, extent=1.0, n_iter=max(2, n_iter // 4),
                    subsets=min(10, sino.n_views))
    if method == "sirt":
        return sirt(sino, size=size, extent=1.0, n_iter=n_iter, projector="linear")
    if method == "sirt_glint":
        return sirt(sino, size=size, extent=1.0, n_iter=n_iter, projector="linear",
                    weights=glint_weights(sino))
    if method == "cgls":
        return cgls(sino, size=size, extent=1.0, n_iter=max(5, n_iter // 2),
                    projector="linear")
    return tv_fista(sino, size=size, extent=1.0, n_iter=n_iter)


def _ideal(scene, ladar, size):
    total = None
    for shape in scene.shapes:
        lone = Scene([type(shape)(**{**_fields(shape), "material": Lambertian(albedo=1.0)})])
        img = fbp(simulate(lone, ladar), size=size, extent=1.0).values
        total = img if total is None else total + img
    return total


def _fields(shape):
    return {f.name: getattr(shape, f.name) for f in fields(shape) if f.init}


def _bands(scene, bin_width, size):
    """Sample points across every boundary: (points (n_surface, n_across, 2), step) and the
    (size, size) mask of the ±2-bin bands."""
    across = np.linspace(-2.0, 2.0, 17) * bin_width
    pts = []
    for sh in scene.shapes:
        t = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
        n = np.stack([np.cos(t), np.sin(t)], axis=1)
        p = np.asarray(sh.center) + sh.radius * n
        pts.append(p[:, None, :] + across[None, :, None] * n[:, None, :])
    c = -1.0 + (np.arange(size) + 0.5) * (2.0 / size)
    X, Y = np.meshgrid(c, c)
    band = np.zeros((size, size), bool)
    for sh in scene.shapes:
        band |= np.abs(np.hypot(X - sh.center[0], Y - sh.center[1]) - sh.radius) <= (
            2.0 * bin_width + 2.0 / size)
    return np.concatenate(pts), band


def _line_density(values, points):
    img = Image(values, 1.0)
    flat = points.reshape(-1, 2)
    return img.sample(flat).reshape(points.shape[:2]).mean(axis=1)


def _error(img, ideal, points):
    """Surface error: the spread of (line density / the ideal's) along the boundaries, in
    4° arcs (a few pixels: speckle finer than that is not judged); None when the
    reconstruction has no surface left."""
    arcs = lambda v: v.reshape(-1, _ARC).mean(axis=1)      # noqa: E731
    ratio = arcs(_line_density(img, points)) / arcs(_line_density(ideal, points))
    mean = float(np.mean(ratio))
    return float(np.std(ratio) / abs(mean)) if abs(mean) > 1e-12 else None


def _clutter(img, band, inside):
    total = float(np.abs(img[inside]).sum())
    return float(np.abs(img[inside & ~band]).sum()) / total if total > 0 else 0.0


def _noisy(sino, photons, seed, speckle_cells=None, background=0.0):
    """The sinogram as a photon-counting receiver sees it: scaled so that its brightest
    bin holds ``photons`` photoelectrons, with speckle of ``speckle_cells`` cells per bin
    and ``background`` photoelectrons per bin (:func:`meshladar.noise.draw_noise`, one
    seeded draw), the mean background subtracted (as a receiver that measured it would),
    scaled back."""
    k = photons / float(sino.values.max())
    noise = Noise(speckle_cells=speckle_cells, background_rate=background)
    counts = draw_noise(noise, sino.values * k, 1.0, 1, seed)[0] - background
    return dataclasses.replace(sino, values=counts / k,
                               info=dict(sino.info, photons_at_peak=photons,
                                         speckle_cells=speckle_cells,
                                         background_per_bin=background))


def run(setting="quick", *, methods=METHODS, spacings=SPACINGS, photons=None, seed=0,
        speckle_cells=None, background=0.0):
    """Every (phantom, spacing, method): a dict row with ``error``, the phantom's metric
    (``darkening`` or ``visibility``) and ``seconds``; returns (rows, images) with images
    keyed by (phantom, spacing, method). With ``photons``, each sinogram carries
    photon-counting noise with that many photoelectrons in its brightest bin (seeded),
    and optionally speckle (``speckle_cells`` M ≥ 1 per bin) and a ``background`` of
    photoelectrons per bin (subtracted in the mean, its noise kept).

    The phantoms: ``"disk_b0.99"`` (the paper's disk, diffuse b = 0.99) and
    ``"pair_gray_al"`` (the disk pair, gray large disk and aluminium small one). Their
    sinograms are analytic (Eq. 8), views at ``0, sp, 2 sp, ...`` below 360° for each
    spacing sp, bins of width 1.6 / n_bins centred on range 0; every image is
    size × size over [−1, 1]². The ideal and the measures are the module docstring's.

    Parameters
    ----------
    setting : {"quick", "full"}
        Image size, range bins and iterations: quick (128, 128, 40), full (256, 256,
        100).
    methods : sequence of str, keyword-only
        One or more names from :data:`METHODS` (default all).
    spacings : sequence of float, keyword-only
        One or more view spacings in degrees, each > 0 (default :data:`SPACINGS`).
    photons : float, optional, keyword-only
        > 0: photoelectrons in each noisy sinogram's brightest bin (default None: no
        noise).
    seed : int, keyword-only
        Seed of the noise; each spacing draws from ``[seed, int(1000 × spacing)]``
        (default 0).
    speckle_cells : float, optional, keyword-only
        M, speckle cells per bin, with ``photons`` (default None: no speckle).
    background : float, keyword-only
        >= 0: background photoelectrons per bin, with ``photons`` (default 0.0).

    Returns
    -------
    rows : list of dict
        One per (phantom, spacing, method), in that order: ``phantom``, ``spacing_deg``,
        ``method``, ``photons``, ``speckle_cells``, ``background``, ``error`` (None when
        the reconstruction has no surface left), ``clutter``, ``seconds`` (the
        reconstruction's wall time), and ``darkening``
        (:func:`meshladar.studies.paper.disk_darkening`, the disk) or ``visibility``
        (:func:`meshladar.studies.paper.ring_visibility`, the pair; None when the
        aluminium ring is gone).
    images : dict
        (phantom, spacing_deg, method) → the (size, size) image values.

    Raises
    ------
    ParameterError
        When ``setting``, a method or a spacing is none of the above, ``speckle_cells``
        or a non-zero ``background`` is given without ``photons``, ``photons`` is not
        > 0, or ``background`` is negative; before any work.
    """
    methods, spacings = _checked_runs(setting, methods, spacings)
    photons, background = _checked_noise(photons, speckle_cells, background)
    size, n_bins, n_iter = _SETTINGS[setting]
    rows, images = [], {}
    bins = Ladar.centered(n_bins, 1.6 / n_bins).bin_edges
    for name, scene in _phantoms().items():
        judge = _judge(scene, bins, size)
        for sp in spacings:
            ladar = Ladar(np.arange(0.0, 360.0, sp), bins)
            sino = simulate(scene, ladar)
            if photons is not None:
                sino = _noisy(sino, photons, [seed, int(sp * 1000)], speckle_cells,
                              background)
            for method in methods:
                measured, img = _measure(name, method, sino, judge, size, n_iter)
                rows.append({"phantom": name, "spacing_deg": sp, "method": method,
                             "photons": photons, "speckle_cells": speckle_cells,
                             "background": background, **measured})
                images[(name, sp, method)] = img.values
    return rows, images


def _checked_runs(setting, methods, spacings):
    """``setting``, ``methods`` and ``spacings`` checked (a name outside :data:`METHODS`
    would otherwise run as "tv" under its own label; a string would run each letter)."""
    check_choice("setting", setting, tuple(_SETTINGS))
    for name, value in (("methods", methods), ("spacings", spacings)):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or not len(value):
            raise ParameterError(f"{name} must be a non-empty list or tuple; got {short(value)}")
    methods = tuple(check_choice(f"methods[{i}]", m, METHODS) for i, m in enumerate(methods))
    spacings = tuple(check_real(f"spacings[{i}]", sp, low=0.0, low_open=True)
                     for i, sp in enumerate(spacings))
    return methods, spacings


def _checked_noise(photons, speckle_cells, background):
    """``photons`` and ``background`` checked (speckle and background need photons)."""
    if photons is None and (speckle_cells is not None or background):
        raise ParameterError("speckle_cells and background need photons (the signal's "
                             "scale in photoelectrons)")
    if photons is not None:
        photons = check_real("photons", photons, low=0.0, low_open=True)
    return photons, check_real("background", background, low=0.0)


@dataclasses.dataclass(frozen=True)
class _Judge:
    """What a phantom's reconstructions are judged against: its ``scene``, the ``ideal``
    image, the sample ``points`` across its boundaries and the mask of their ``band``
    (:func:`_bands`), the mask ``inside`` its bounding circle and the ``bin_width``."""

    scene: Scene
    ideal: np.ndarray
    points: np.ndarray
    band: np.ndarray
    inside: np.ndarray
    bin_width: float


def _judge(scene, bins, size):
    """The :class:`_Judge` of ``scene`` for range bins ``bins`` and size × size images."""
    c = -1.0 + (np.arange(size) + 0.5) * (2.0 / size)
    X, Y = np.meshgrid(c, c)
    (cx, cy), radius = scene.bounding_circle()
    inside = np.hypot(X - cx, Y - cy) < radius * 1.05
    bin_width = float(np.diff(bins)[0])
    points, band = _bands(scene, bin_width, size)
    ideal = _ideal(scene, Ladar(np.arange(0.0, 360.0, 1.0), bins), size)
    return _Judge(scene, ideal, points, band, inside, bin_width)


def _measure(name, method, sino, judge, size, n_iter):
    """One method's reconstruction of ``sino`` and its measures: ({``error``, ``clutter``,
    ``seconds`` and the phantom's ``darkening`` or ``visibility``}, the image)."""
    used = {"fbp_log": log_radiance, "fbp_clip": clip_radiance}.get(
        method, lambda x: x)(sino)
    power = float(used.total().mean())      # the input's own level
    t0 = time.perf_counter()
    img = _reconstruct(method, sino, size, n_iter, judge.scene)
    seconds = time.perf_counter() - t0
    row = {"error": _error(img.values, judge.ideal, judge.points),
           "clutter": _clutter(img.values, judge.band, judge.inside), "seconds": seconds}
    if name.startswith("disk"):
        row["darkening"] = paper.disk_darkening(img, 0.8, power)[0]
    else:
        gray, al = judge.scene.shapes
        vis = paper.ring_visibility(img, gray, al, judge.bin_width)
        # None where the aluminium ring is gone (the ratio is undefined)
        row["visibility"] = vis if np.isfinite(vis) else None
    return row, img


def report(rows):
    """The study's table as text lines.

    Parameters
    ----------
    rows : list of dict
        The rows :func:`run` returns.

    Returns
    -------
    list of str
        A header, then one line per row: phantom, spacing, method, error, clutter, the
        metric's kind (``dark`` or ``vis``) and value (``—`` for None) and seconds.
    """
    out = [f"  {'phantom':<14} {'spacing':>7} {'method':<11} {'error':>7} {'clutter':>7} "
           f"{'metric':>11} {'seconds':>8}"]
    for r in rows:
        metric = r.get("darkening", r.get("visibility"))
        kind = "dark" if "darkening" in r else "vis"
        err = "—" if r["error"] is None else f"{r['error']:.3f}"
        metric = "—" if metric is None else f"{metric:.3f}"
        out.append(f"  {r['phantom']:<14} {r['spacing_deg']:>6g}° {r['method']:<11} "
                   f"{err:>7} {r['clutter']:7.3f} {kind:>4} {metric:>6} "
                   f"{r['seconds']:8.2f}")
    return out
