"""The paper's experiments (Jin & Levine 2009, Figs 5-11) and the numbers behind its findings.

:func:`run` computes every figure's sinograms and reconstructions with the paper's set-up
(A/256 range bins with A = 0.8, 360 views at 1°, the analytic forward model) and measures
each finding as a number; ``meshladar.viz.paper`` draws the figures from the saved result.
The functions that measure them (:func:`disk_darkening` and the others) are defined in the
private ``_paper_metrics`` beside this module, and importable from here.

Metrics (dimensionless, defined here and asserted in tests/studies/test_paper.py):

``darkening``
    Edge darkening of a disk of radius R: (mean of the image's radial profile over the band
    just inside the surface, 0.90 R < ρ < 0.97 R, minus its mean over the deeper interior,
    0.60 R < ρ < 0.80 R) × πR² / P̄, with P̄ the mean returned power per view (the sum of a
    view's bins). Normalising by the returned power, not by the interior level, matters:
    even the exact 360° FBP of a Lambertian disk has a small negative interior pedestal and
    a log-divergent dip at the centre (the paper's "sampling artifact"); the interior band
    starts at 0.6 R, where that pedestal has flattened, and the surface band stops at
    0.97 R, short of the one-pixel FBP side-lobe every ring has. ≈ 0 for b = 0; negative
    for b = 0.99; far more negative for the e = 0.007 glint.
``darkening_width``
    Radial width (in units of R) of the trough between 0.6 R and 0.97 R where the profile is
    below the interior level by more than half the trough's depth: narrower for glints.
``ends_darkening`` / ``sides_darkening``
    The ellipse's darkening in the band 0.03-0.10 B inside its boundary (B the semi-minor
    axis, offsets along the inward normal), averaged over the tapered ends (|cos t| > 0.95
    in the eccentric angle) and over the flat sides (|sin t| > 0.95), same normalisation
    with the ellipse's area. The paper: concentrated at the ends.
``power.<panel>.<metric>``
    The same metrics with received power (``radiometry="power"``, one cos θ more than
    Eq. 8) as the data, for the panels in :data:`POWER_PANELS`. The question the paper did
    not ask — is a Lambertian surface still reconstructed without darkening when the data
    are received power? — has a two-part answer (measured, 512² images): a Lambertian
    disk's surface band stays level with its interior (−0.04, against +0.07 with Eq. 8:
    by symmetry every boundary point sees the same incidences), but a Lambertian
    ellipse's tapered ends darken 7× more (−0.82 against −0.12), and every glossy
    coating's darkening deepens (disk b = 0.99: −2.02 against −1.36; ellipse ends −5.29
    against −4.07). Log and clip input recover the gray disk as before (0.91, 0.87).
``visibility``
    For a disk pair: the gray disk's ring mean (image averaged over the annulus within two
    range bins of its circle) over the aluminium disk's. Near 0 in Fig. 10 (the gray disk is
    "virtually invisible"); restored by the log (Fig. 11a) and by clipping (Fig. 11b).
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np

from .. import materials
from .. import phantoms as _phantoms
from ..brdf import SandfordRobertson
from .._validate import check_count, check_real
from ..errors import EnergyConservationWarning, ParameterError
from ..forward import simulate
from ..forward.sampling import checked_by_caller
from ..ladar import Ladar
from ..meshes import fibonacci_sphere
from ..reconstruct import clip_radiance, fbp, log_radiance
from ..scene import Scene
from ..reconstruct.volumes import fbp3d as radon3d
from ._paper_metrics import (_shell_peak, disk_darkening, ellipse_darkening, ring_visibility,
                             shell_darkening)

__all__ = ["FIGURES", "run", "disk_darkening", "ellipse_darkening", "ring_visibility",
           "IMAGE_SIZE", "IMAGE_EXTENT", "MIN_SIZE", "FINDINGS", "RELATIVE_TOLERANCE"]

#: Reconstruction grid of the figures: 512² pixels over [−1, 1]².
IMAGE_SIZE = 512
IMAGE_EXTENT = 1.0
_A = 0.8                       # the paper's disk radius, which sets the A/256 bins

#: The findings docs/guide/paper.md states (their 512² figures), each with the absolute part
#: a of its tolerance: a finding holds at a size when its value v there and its 512²
#: figure f meet |v − f| ≤ a + :data:`RELATIVE_TOLERANCE` × |f| (a = 0.1 for darkenings
#: and visibilities, 0.01 for trough widths, in units of the radius).
FINDINGS = {
    "disk_b0.darkening": 0.1, "disk_b0.99.darkening": 0.1, "disk_e0.007.darkening": 0.1,
    "disk_e0.007.darkening_width": 0.01, "disk_b0.99.darkening_width": 0.01,
    "ellipse_b0.ends_darkening": 0.1, "ellipse_b0.99.ends_darkening": 0.1,
    "ellipse_b0.99.sides_darkening": 0.1, "pair_gray_al.visibility": 0.1,
    "pair_al_gray.visibility": 0.1, "pair_gray_al_log.visibility": 0.1,
    "pair_gray_al_clip.visibility": 0.1, "power.disk_b0.darkening": 0.1,
    "power.ellipse_b0.ends_darkening": 0.1, "power.disk_b0.99.darkening": 0.1,
    "power.ellipse_b0.99.ends_darkening": 0.1, "power.pair_gray_al_log.visibility": 0.1,
    "power.pair_gray_al_clip.visibility": 0.1}
#: The relative part of every finding's tolerance (:data:`FINDINGS`).
RELATIVE_TOLERANCE = 0.05
#: The smallest ``size`` :func:`run` takes (at its default extent; pixels no coarser than
#: 2/475 at any other): from 475 up, every finding of :data:`FINDINGS` is within its
#: tolerance of its 512² figure at every size measured (each from 97 to 560, every 8th to
#: 1024). Below, the b = 0.99 ellipse's sides leave it first (−0.45 at 474, −0.33 at 512:
#: FBP's pixel grid moves them by ±0.1 from one size to the next), then the Lambertian
#: ellipse's ends (below 327), the clipped pair's visibility (317), the b = 0.99 disk's
#: trough width (306), the gray disk's visibility (238; −0.47 against 0.010 at 128); at
#: 1 pixel the visibilities are NaN.
MIN_SIZE = 475


def _diffuse(b):
    with warnings.catch_warnings():
        # the paper's ρd = 1, b = 0.99 surface is knowingly not energy-conserving (Sec. 4.A)
        warnings.simplefilter("ignore", EnergyConservationWarning)
        return SandfordRobertson(1.0, 0.0, b, 1.0, lobes="diffuse",
                                           name=f"diffuse b={b:g}")


def _pair(big, small):
    return _phantoms.scene("disk_pair", large=big, small=small)


def _panels():
    """Every reconstruction panel: key → (scene, preprocessing, caption)."""
    gray, al = materials.DARK_GRAY, materials.ALUMINUM
    disk = functools.partial(_phantoms.scene, "disk")                 # radius A = 0.8
    ellipse = functools.partial(_phantoms.scene, "ellipse")           # 0.6 × 0.3
    return {
        "disk_b0": (disk(_diffuse(0.0)), None, "disk A = 0.8, diffuse b = 0 (Lambertian)"),
        "disk_b0.99": (disk(_diffuse(0.99)), None, "disk A = 0.8, diffuse b = 0.99"),
        "ellipse_b0": (ellipse(_diffuse(0.0)), None, "ellipse 0.6 × 0.3, diffuse b = 0"),
        "ellipse_b0.99": (ellipse(_diffuse(0.99)), None, "ellipse 0.6 × 0.3, diffuse b = 0.99"),
        "disk_e1": (disk(materials.glint(1.0)), None, "disk, specular only, e = 1"),
        "disk_e0.007": (disk(materials.glint(0.007)), None, "disk, specular only, e = 0.007"),
        "pair_gray_gray": (_pair(gray, gray), None, "disk pair, dark gray on both"),
        "pair_al_al": (_pair(al, al), None, "disk pair, aluminium on both"),
        "pair_gray_al": (_pair(gray, al), None, "gray large disk, aluminium small disk"),
        "pair_al_gray": (_pair(al, gray), None, "aluminium large disk, gray small disk"),
        "pair_gray_al_log": (_pair(gray, al), "log", "Fig. 10(a) with log(radiance) input"),
        "pair_gray_al_clip": (_pair(gray, al), "clip", "Fig. 10(a) clipped at 0.008 × max"),
    }


#: Figure number → (title, panel keys).
FIGURES = {
    5: ("Range profiles of a diffuse disk", ["disk_b0", "disk_b0.99"]),
    6: ("Diffuse disk: reconstructions and centre slices", ["disk_b0", "disk_b0.99"]),
    7: ("Diffuse ellipse", ["ellipse_b0", "ellipse_b0.99"]),
    8: ("Specular disk", ["disk_e1", "disk_e0.007"]),
    9: ("Disk pair, one coating", ["pair_gray_gray", "pair_al_al"]),
    10: ("Disk pair, mixed coatings", ["pair_gray_al", "pair_al_gray"]),
    11: ("Recovering the diffuse disk", ["pair_gray_al_log", "pair_gray_al_clip"]),
}


#: Panels measured again with received power (``radiometry="power"``) as the data: metrics
#: ``power.<key>.<metric>``.
POWER_PANELS = ("disk_b0", "disk_b0.99", "ellipse_b0", "ellipse_b0.99", "pair_gray_al",
                "pair_gray_al_log", "pair_gray_al_clip")


def _prepared(sino, prep):
    if prep == "log":
        return log_radiance(sino)
    if prep == "clip":
        return clip_radiance(sino)
    return sino


def _measure(key, scene, prep, raw, ladar, size, extent, metrics):
    """Reconstruct one panel from its raw sinogram and add its metrics; returns the image."""
    image = fbp(_prepared(raw, prep), size=size, extent=extent)
    power = float(raw.total().mean())
    shapes = scene.shapes
    name = key.removeprefix("power.")
    if name.startswith("disk"):
        d, w = disk_darkening(image, _A, power)
        metrics[f"{key}.darkening"], metrics[f"{key}.darkening_width"] = d, w
    elif name.startswith("ellipse"):
        e, s = ellipse_darkening(image, shapes[0], power)
        metrics[f"{key}.ends_darkening"], metrics[f"{key}.sides_darkening"] = e, s
    elif name.startswith("pair"):
        mats = [sh.material for sh in shapes]
        if materials.DARK_GRAY in mats and materials.ALUMINUM in mats:
            g = shapes[mats.index(materials.DARK_GRAY)]
            a = shapes[mats.index(materials.ALUMINUM)]
            metrics[f"{key}.visibility"] = ring_visibility(
                image, g, a, float(np.min(np.diff(ladar.bin_edges))))
    return image


def _checked_size(size, extent):
    """``size``, refused below :data:`MIN_SIZE` (scaled up with an ``extent`` above the
    default's, so that pixels are no coarser), before any work."""
    extent = check_real("extent", extent, low=0.0, low_open=True)
    minimum = max(MIN_SIZE, math.ceil(MIN_SIZE * extent / IMAGE_EXTENT - 1e-9))
    integer = isinstance(size, (int, np.integer)) and not isinstance(size, (bool, np.bool_))
    if integer and size < minimum:
        raise ParameterError(
            f"size={size} is below the minimum {minimum}"
            + (f" at extent={extent:g}" if minimum != MIN_SIZE else "")
            + ": the paper's findings hold, each within its tolerance of its 512x512 figure "
            f"(docs/guide/paper.md), from {minimum} pixels a side up; give size >= "
            f"{minimum} (default {IMAGE_SIZE})")
    return check_count("size", size, low=minimum)


def run(*, size=IMAGE_SIZE, extent=IMAGE_EXTENT, ladar=None):
    """Compute every panel and metric of Figs 5-11.

    Each panel's analytic sinogram (Eq. 8) is reconstructed by FBP (after the panel's log
    or clip preprocessing, :func:`meshladar.reconstruct.log_radiance` and
    :func:`meshladar.reconstruct.clip_radiance` at their defaults) and measured; the
    panels of :data:`POWER_PANELS` are measured again from received power.

    Parameters
    ----------
    size : int, keyword-only
        Pixels per side of every reconstruction (default :data:`IMAGE_SIZE`, 512), at
        least :data:`MIN_SIZE` (475), where the findings hold.
    extent : float, keyword-only
        Half-width of the reconstructions' square about the origin, scene units (default
        :data:`IMAGE_EXTENT`, 1.0); above it, ``size`` must be at least :data:`MIN_SIZE`
        × ``extent`` (pixels no coarser than at 475 over the default).
    ladar : Ladar, optional, keyword-only
        The views and bins (default :meth:`meshladar.ladar.Ladar.paper` with A = 0.8: 360
        views at 1°, 512 bins of A/256 over [−A, A]). The disk metrics take the paper's
        radius 0.8 whatever the ladar.

    Returns
    -------
    dict
        ``sinograms``: key → (n_views, n_bins) values ((360, 512) with the default ladar),
        preprocessed as the panel's image was; ``images``: key → (size, size) values;
        ``bin_edges``, ``angles_deg``, ``extent``, ``size``, ``captions``, ``outlines``
        (each panel's shapes, for the figures' colour scales), and ``metrics``: a flat
        dict of the findings' numbers (see the module docstring).

    Raises
    ------
    ParameterError
        When ``size`` is not an integer of at least :data:`MIN_SIZE` (scaled with
        ``extent``), or ``extent`` is not a positive real, before any work: below it the
        findings do not hold (:data:`MIN_SIZE`).
    """
    size = _checked_size(size, extent)
    ladar = Ladar.paper(_A) if ladar is None else ladar
    panels = _panels()
    sinos, images, captions, metrics, outlines = {}, {}, {}, {}, {}
    raw, raw_power = {}, {}
    for key, (scene, prep, caption) in panels.items():
        base = key.replace("_log", "").replace("_clip", "")
        if base not in raw:
            raw[base] = simulate(scene, ladar)
        image = _measure(key, scene, prep, raw[base], ladar, size, extent, metrics)
        sinos[key], images[key], captions[key] = _prepared(raw[base], prep).values, \
            image.values, caption
        outlines[key] = [{"center": list(sh.center), "axes": list(sh.axes),
                          "angle": sh.angle} for sh in scene.shapes]
    # the question the paper did not ask: the same panels with received power as the data
    for key in POWER_PANELS:
        scene, prep, _ = panels[key]
        base = key.replace("_log", "").replace("_clip", "")
        if base not in raw_power:
            raw_power[base] = simulate(scene, ladar, radiometry="power")
        _measure(f"power.{key}", scene, prep, raw_power[base], ladar, size, extent, metrics)
    return {"sinograms": sinos, "images": images, "captions": captions, "metrics": metrics,
            "outlines": outlines,
            "bin_edges": ladar.bin_edges, "angles_deg": ladar.angles_deg, "extent": extent,
            "size": size}


#: The 3-D study's set-up: spheres of radius 0.5 (single) and a pair (gray large, aluminium
#: small), seen from Fibonacci directions over the whole sphere.
SPHERE_3D = 0.5
PAIR_3D = (((-0.2, 0.0, 0.0), 0.4), ((0.45, 0.1, 0.0), 0.15))


def _sphere_scene(parts):
    import trimesh

    meshes = []
    for (c, r), m in parts:
        s = trimesh.creation.icosphere(subdivisions=5 if r < 0.3 else 6, radius=r)
        s.apply_translation(c)
        meshes.append((s, m))
    return Scene.from_meshes(meshes)


def _volume_of(ladar, rays_per_bin, grid, scene):
    """A scene's mesh profiles (smooth normals) and their 3-D inversion on ``grid``."""
    with checked_by_caller():                  # the glint sphere is undersampled on purpose
        sino = simulate(scene, ladar, model="mesh", normals="smooth",
                        rays_per_bin=rays_per_bin)
    return sino, radon3d(sino, **grid)


def run_3d(*, views=2000, size=128, smooth=1.0, extent=0.8, rays_per_bin=2.0):
    """The paper's findings measured in 3-D (``meshladar study tomography3d``): spheres
    seen from ``views`` Fibonacci directions (Eq. 8, as the paper; the mesh model with
    smooth normals and ``rays_per_bin`` rays per range bin across), reconstructed by
    :func:`meshladar.reconstruct.volumes.fbp3d` on ``size``³ voxels with ``smooth``.

    Metrics (``3d.*``): ``sphere_<coating>.darkening`` (:func:`shell_darkening`) for the
    Lambertian (b = 0), diffuse b = 0.99 and glint e = 0.007 coatings;
    ``pair_gray_al.visibility`` (the gray sphere's shell peak over the aluminium one's, and
    with log and clip input); ``pair.shadow_streaks`` (RMS, outside both spheres, of the
    pair's volume minus the two spheres reconstructed alone, over the gray shell's peak:
    what mutual shadowing adds). Returns (metrics, volumes).

    The glint sphere's lobe (e = 0.007) gets fewer rays across it than the mesh model's
    lobe check asks (0.27 at 2 rays per bin in the quick setting): its shell darkening is
    that of undersampled data, at every setting alike, and the check is silenced here.

    Parameters
    ----------
    views : int, keyword-only
        Fibonacci view directions (default 2000).
    size : int, keyword-only
        Voxels per side, and range bins over [−``extent``, ``extent``] (default 128).
    smooth : float, keyword-only
        Gaussian smoothing of each profile before the inversion, in bins (default 1.0).
    extent : float, keyword-only
        Half-width of the cube and of the bins' span, scene units (default 0.8).
    rays_per_bin : float, keyword-only
        The mesh model's rays per range bin across (default 2.0).

    Returns
    -------
    metrics : dict of str to float
        ``3d.sphere_b0.darkening``, ``3d.sphere_b0.99.darkening``,
        ``3d.sphere_e0.007.darkening``, ``3d.pair_gray_al.visibility`` (and ``_log``,
        ``_clip``) and ``3d.pair.shadow_streaks``.
    volumes : dict of str to Volume
        ``sphere_b0``, ``sphere_b0.99``, ``sphere_e0.007``, ``pair_gray_al``,
        ``pair_gray_al_log`` and ``pair_gray_al_clip``.
    """
    ladar = Ladar(None, np.linspace(-extent, extent, size + 1),
                  view_vectors=fibonacci_sphere(views))

    volume = functools.partial(_volume_of, ladar, rays_per_bin,
                               {"size": size, "extent": extent, "smooth": smooth})
    metrics, volumes = {}, {}
    origin = (0.0, 0.0, 0.0)
    for key, m in (("b0", _diffuse(0.0)), ("b0.99", _diffuse(0.99)),
                   ("e0.007", materials.glint(0.007))):
        sino, vol = volume(_sphere_scene([((origin, SPHERE_3D), m)]))
        volumes[f"sphere_{key}"] = vol
        metrics[f"3d.sphere_{key}.darkening"] = shell_darkening(
            vol, SPHERE_3D, float(sino.total().mean()))
    (cg, rg), (ca, ra) = PAIR_3D
    gray, al = materials.DARK_GRAY, materials.ALUMINUM
    pair = _sphere_scene([(PAIR_3D[0], gray), (PAIR_3D[1], al)])
    with checked_by_caller():                  # aluminium's glint: undersampled on purpose
        sino = simulate(pair, ladar, model="mesh", normals="smooth",
                        rays_per_bin=rays_per_bin)
    for prep in (None, "log", "clip"):
        vol = radon3d(_prepared(sino, prep), size=size, extent=extent, smooth=smooth)
        key = "pair_gray_al" + ("" if prep is None else f"_{prep}")
        volumes[key] = vol
        metrics[f"3d.{key}.visibility"] = _shell_peak(vol, cg, rg) / _shell_peak(vol, ca, ra)
    alone = [volume(_sphere_scene([part]))[1].values
             for part in ((PAIR_3D[0], gray), (PAIR_3D[1], al))]
    both = volumes["pair_gray_al"]
    X, Y, Z = np.meshgrid(both.x, both.y, both.z, indexing="xy")
    pts = np.stack([X, Y, Z], -1).transpose(2, 0, 1, 3)           # (z, y, x, 3)
    outside = ((np.linalg.norm(pts - np.asarray(cg), axis=-1) > 1.15 * rg)
               & (np.linalg.norm(pts - np.asarray(ca), axis=-1) > 1.15 * ra)
               & (np.linalg.norm(pts, axis=-1) < extent))
    extra = both.values - alone[0] - alone[1]
    metrics["3d.pair.shadow_streaks"] = float(
        np.sqrt(np.mean(extra[outside] ** 2)) / _shell_peak(both, cg, rg))
    return metrics, volumes
