"""BRDF and shadow compensation (meshladar.reconstruct.compensation): the segment projector
against the exact disk sinogram, surface points and normals against the true circle, the shadow map
against exact ray-disk geometry, and the compensated disk: no edge darkening, a uniform
surface at the level ⟨h⟩ · length."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import meshladar as ml
from meshladar import materials
from meshladar.studies import paper
from meshladar.brdf import Lambertian
from meshladar.errors import ParameterError
from meshladar.ladar import Ladar
from meshladar.reconstruct._kernels import surface_project
from meshladar.reconstruct.compensation import (Surface, SurfaceProjector, compensate,
                                                estimate_surface, surface_weights)
from meshladar.reconstruct.iterative import sirt
from meshladar.scene import Scene
from meshladar.shapes import Disk

SIZE, R = 256, 0.8
LADAR = Ladar(np.arange(0.0, 360.0, 1.0), Ladar.centered(256, 1.6 / 256).bin_edges)
#: Exact segments tile the circle: the projector's only error is the chords' sag.
SEGMENT_TOL = 0.012
#: A compensated surface's level against ⟨h⟩ · length (measured 1-2 % at 256²).
LEVEL_TOL = 0.06
#: Angular non-uniformity (std / mean over 0.2 rad arcs) of a compensated ring (measured
#: 0.02-0.04).
UNIFORMITY_TOL = 0.08


def _mean_weight(material, radiometry="paper"):
    """⟨h⟩ = (1/π) ∫₀^{π/2} h(θ) dθ by adaptive quadrature."""
    def h(t):
        v = float(material.projected(np.cos(t), np.sin(t)))
        return v * math.cos(t) if radiometry == "power" else v
    return quad(h, 0.0, 0.5 * math.pi, limit=200)[0] / math.pi


def _disk(material):
    return ml.simulate(Scene([Disk((0.0, 0.0), R, material)]), LADAR)


def _grid_xy(size=SIZE):
    c = -1 + (np.arange(size) + 0.5) * 2 / size
    return np.meshgrid(c, c)


def _ring_stats(image):
    """(∫ image over the ring band, angular std/mean over 0.2 rad arcs)."""
    X, Y = _grid_xy(image.size)
    band = np.abs(np.hypot(X, Y) - R) < 0.05
    v, a = image.values[band], np.arctan2(Y, X)[band]
    arcs = np.array([v[(a >= t) & (a < t + 0.2)].sum() for t in np.arange(-np.pi, 3.0, 0.2)])
    return float(v.sum() * (2 / image.size) ** 2), float(arcs.std() / arcs.mean())


def test_segment_projector_matches_the_exact_disk_sinogram():
    """Uniform segments tiling the circle, each carrying ⟨h⟩ per unit length with view
    weights h/⟨h⟩, reproduce the analytic Lambertian sinogram."""
    m = Lambertian(1.0)
    sino = _disk(m)
    n = 1000
    t = (np.arange(n) + 0.5) * 2 * np.pi / n
    pts = R * np.stack([np.cos(t), np.sin(t)], 1)
    surf = Surface(pts, np.zeros(n, int), np.zeros(n, int), pts / R, SIZE, 1.0, (0.0, 0.0))
    H = surface_weights(surf, LADAR.angles_deg, m, blur_deg=0.0)
    phi = np.deg2rad(LADAR.angles_deg)
    arc = 2 * np.pi * R / n
    out = np.zeros(sino.shape)
    surface_project(np.full(n, _mean_weight(m) * arc), pts[:, 0].copy(), pts[:, 1].copy(),
                    -pts[:, 1] / R, pts[:, 0] / R, np.full(n, 0.5 * arc), H, np.cos(phi),
                    np.sin(phi), LADAR.bin_edges[0], 1 / np.diff(LADAR.bin_edges)[0], out)
    err = np.linalg.norm(out - sino.values) / np.linalg.norm(sino.values)
    assert err < SEGMENT_TOL


@pytest.mark.parametrize("smooth", [0.0, 2.0])
def test_projector_stays_on_the_surface(smooth):
    """Aᵀ is zero off the surface, with and without smoothing along the surface; the
    smoother averages (a uniform surface stays uniform). Its adjoint is exact:
    tests/reconstruct/test_operators.py, with every projector."""
    sino = _disk(Lambertian(1.0))
    surf = estimate_surface(ml.fbp(ml.log_radiance(sino), size=SIZE), sino, shadows=False)
    H = surface_weights(surf, LADAR.angles_deg, Lambertian(1.0))
    A = SurfaceProjector(surf, LADAR.angles_deg, LADAR.bin_edges, H, smooth)
    if smooth:
        assert np.allclose(A.smooth @ np.ones(surf.rows.size), 1.0, rtol=0, atol=1e-12)
    y = np.random.default_rng(0).random(sino.shape)
    assert np.all((A.T @ y)[~surf.mask] == 0)


def test_surface_points_and_normals_follow_the_circle():
    """Steger points lie within a bin of the circle, one per pixel it crosses, and the
    normals point outward within a few degrees."""
    sino = _disk(paper._diffuse(0.99))
    surf = estimate_surface(ml.fbp(ml.log_radiance(sino), size=SIZE), sino)
    rad = np.hypot(*surf.points.T)
    assert np.all(np.abs(rad - R) < 1.6 / 256)
    length = 2 * np.pi * R / (2 / SIZE)                    # circumference, pixels
    assert 0.9 * length < rad.size < 1.3 * length
    radial = surf.points / rad[:, None]
    cos_err = np.sum(surf.normals * radial, axis=1)
    assert np.all(cos_err > math.cos(math.radians(15)))
    assert math.degrees(math.sqrt(np.mean(np.arccos(np.clip(cos_err, -1, 1)) ** 2))) < 5.0
    # a convex disk shadows nothing it faces (a few glancing staircase rays allowed)
    phi = np.deg2rad(LADAR.angles_deg)
    front = surf.normals[:, :1] * np.cos(phi) + surf.normals[:, 1:] * np.sin(phi) > 0
    assert (surf.shadowed & front).sum() / front.sum() < 0.03


def test_shadow_map_matches_exact_geometry_on_the_disk_pair():
    """For the paper's disk pair, 'another surface between the point and the ladar' from
    the first reconstruction agrees with exact ray-disk intersection on ≥ 93 % of the
    front-facing point-views of the points on the true boundaries (measured 99 %)."""
    scene = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    sino = ml.simulate(scene, LADAR)
    surf = estimate_surface(ml.fbp(ml.log_radiance(sino), size=SIZE), sino)
    big, small = scene.shapes
    phi = np.deg2rad(LADAR.angles_deg)
    w = np.stack([np.cos(phi), np.sin(phi)], 1)

    def blocked(p, disk):
        oc = p - np.asarray(disk.center)
        b = oc @ w.T
        disc = b * b - (np.sum(oc * oc, axis=1)[:, None] - disk.radius ** 2)
        return (disc > 0) & (-b - np.sqrt(np.maximum(disc, 0)) > 0)

    d_big = np.abs(np.hypot(*(surf.points - big.center).T) - big.radius)
    d_small = np.abs(np.hypot(*(surf.points - small.center).T) - small.radius)
    on_big = d_big < d_small
    truth = np.where(on_big[:, None], blocked(surf.points, small), blocked(surf.points, big))
    # judged on the points that lie on a true boundary (artefact points inside a disk are
    # rightly hidden by their own disk, which the two-disk truth above does not model)
    on_surface = np.minimum(d_big, d_small) < 2 * 1.6 / 256
    assert on_surface.mean() > 0.8
    front = (surf.normals @ w.T > 0) & on_surface[:, None]
    assert ((surf.shadowed == truth) & front).sum() / front.sum() >= 0.93
    assert (truth & front).sum() > 0.05 * front.sum()            # the test has shadows


def test_shadow_awareness_drops_hidden_points_on_the_gray_pair():
    """Fig. 9's gray pair: the shadow map drops ridge artefacts inside the disks (no view
    sees them), so nothing is left off the surfaces (clutter 0.018 → 0 measured), and
    the surfaces come out more even (surface error 0.63 → 0.58 measured)."""
    from meshladar.studies import reconstruction as study

    lad = Ladar(np.arange(0.0, 360.0, 1.0), Ladar.centered(128, 1.6 / 128).bin_edges)
    scene = paper._pair(materials.DARK_GRAY, materials.DARK_GRAY)
    sino = ml.simulate(scene, lad)
    ideal = study._ideal(scene, lad, 128)
    points, band = study._bands(scene, 1.6 / 128, 128)
    X, Y = _grid_xy(128)
    (cx, cy), radius = scene.bounding_circle()
    inside = np.hypot(X - cx, Y - cy) < 1.05 * radius
    got = {}
    for shadows in (True, False):
        img = compensate(sino, materials.DARK_GRAY, size=128, extent=1.0, method="sirt",
                         n_iter=40, shadows=shadows)
        got[shadows] = (study._error(img.values, ideal, points),
                        study._clutter(img.values, band, inside))
    assert got[True][1] < 0.002 < got[False][1]
    assert got[True][0] < got[False][0] - 0.02


@pytest.mark.slow
@pytest.mark.parametrize("material", [paper._diffuse(0.99), Lambertian(1.0)],
                         ids=["b0.99", "lambert"])
@pytest.mark.parametrize("method", ["sirt", "cgls"])
def test_compensation_removes_edge_darkening(material, method):
    """The issue's goal: the b = 0.99 disk's edge darkening (FBP −1.4) within ±0.2, and the
    surface uniform at ⟨h⟩ · 2πR."""
    sino = _disk(material)
    power = float(sino.total().mean())
    img = compensate(sino, material, size=SIZE, extent=1.0, method=method,
                     n_iter=100 if method == "sirt" else 30)
    dark, _ = paper.disk_darkening(img, R, power)
    assert abs(dark) <= 0.2
    level, spread = _ring_stats(img)
    assert abs(level / (_mean_weight(material) * 2 * np.pi * R) - 1) < LEVEL_TOL
    assert spread < UNIFORMITY_TOL
    assert img.info["method"] == "compensated" and img.info["radiometry"] == "paper"
    assert img.info["residuals"][-1] < 0.2
    assert abs(img.info["surface_shift"]) <= 1.6 / 256 + 1e-12
    if not isinstance(material, Lambertian):
        fbp_dark, _ = paper.disk_darkening(ml.fbp(sino, size=SIZE), R, power)
        assert fbp_dark < -1.0


def test_compensation_in_received_power():
    """With radiometry='power' h gains a cos θ; the level is still ⟨h⟩ · 2πR."""
    m = paper._diffuse(0.99)
    sino = ml.simulate(Scene([Disk((0.0, 0.0), R, m)]), LADAR, radiometry="power")
    img = compensate(sino, m, size=SIZE, extent=1.0, method="sirt", n_iter=100)
    level, spread = _ring_stats(img)
    assert img.info["radiometry"] == "power"
    assert abs(level / (_mean_weight(m, "power") * 2 * np.pi * R) - 1) < LEVEL_TOL
    assert spread < UNIFORMITY_TOL


def test_bad_input_is_named():
    sino = _disk(Lambertian(1.0))
    with pytest.raises(ParameterError, match="labels"):
        compensate(sino, [Lambertian(1.0), Lambertian(0.5)], size=64)
    with pytest.raises(ParameterError, match="method"):
        compensate(sino, Lambertian(1.0), size=64, method="art")
    with pytest.raises(ParameterError, match="first"):
        estimate_surface(np.zeros((8, 8)), sino)
    surf = estimate_surface(ml.fbp(sino, size=64), sino, shadows=False)
    with pytest.raises(ParameterError, match="grid"):
        compensate(sino, Lambertian(1.0), size=128, surface=surf)
    with pytest.raises(ParameterError, match="projector"):
        sirt(sino, size=128, projector=SurfaceProjector(
            surf, LADAR.angles_deg, LADAR.bin_edges,
            surface_weights(surf, LADAR.angles_deg, Lambertian(1.0))))
    with pytest.raises(ParameterError, match="uniform"):
        bad = Ladar(LADAR.angles_deg, np.r_[LADAR.bin_edges[:-1], LADAR.bin_edges[-1] + 0.1])
        compensate(ml.simulate(Scene([Disk((0.0, 0.0), R, Lambertian(1.0))]), bad),
                   Lambertian(1.0), size=64)


@pytest.mark.slow
def test_compensation_with_photon_noise():
    """1000 photoelectrons in the brightest bin, Poisson: the noise floor is read off the
    counts' quantum, noise ridges are dropped because the data does not back them, and the
    b = 0.99 disk still comes out without darkening at its level."""
    from meshladar.studies import reconstruction as study
    from meshladar.reconstruct import noise_floor

    m = paper._diffuse(0.99)
    clean = _disk(m)
    noisy = study._noisy(clean, 1000.0, 7)
    assert noise_floor(clean) == pytest.approx(1e-6)
    assert noise_floor(noisy) == pytest.approx(3.0 / 1000.0, rel=0.2)   # three photons
    img = compensate(noisy, m, size=SIZE, extent=1.0, method="sirt", n_iter=100)
    dark, _ = paper.disk_darkening(img, R, float(clean.total().mean()))
    assert abs(dark) <= 0.2
    level, spread = _ring_stats(img)
    assert abs(level / (_mean_weight(m) * 2 * np.pi * R) - 1) < 2 * LEVEL_TOL
    assert spread < 2 * UNIFORMITY_TOL


#: The compensated b = 0.99 disk with the paper's 512 bins, as the README states it: per
#: image size, the line density over ±2 bins of the circle over ⟨h⟩ · 2πR, its spread
#: (std / mean) over 12° arcs and the surface's mean radius less R in bins (measured at
#: 256²: 0.880, 0.079, +0.48; 427²: 0.980, 0.014, 0.00; 512²: 1.002, 0.045, −0.13).
STATED_BAND = {256: (0.88, 0.08, 0.5), 427: (0.98, 0.014, 0.0), 512: (1.0, 0.045, -0.13)}
#: Tolerances on those: level and spread to the digits stated, the offset to a tenth of
#: a bin.
BAND_LEVEL_TOL, BAND_SPREAD_TOL, OFFSET_TOL = 0.006, 0.006, 0.1


def _band_stats(image, bin_width):
    """(the line density over ±2 bins of the circle, its mean × 2πR; its std / mean over
    12° arcs), by bilinear samples: 720 around, 17 across; and the mean radius of the
    ring band (|r − R| < 0.05) weighted by the image, less R, in bins."""
    t = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    across = R + np.linspace(-2.0, 2.0, 17) * bin_width
    pts = across[None, :, None] * np.stack([np.cos(t), np.sin(t)], 1)[:, None, :]
    dens = image.sample(pts.reshape(-1, 2)).reshape(720, 17).mean(axis=1) * 4 * bin_width
    arcs = dens.reshape(-1, 24).mean(axis=1)
    X, Y = _grid_xy(image.size)
    r = np.hypot(X, Y)
    band = np.abs(r - R) < 0.05
    v = image.values[band]
    offset = (float(np.sum(v * r[band]) / np.sum(v)) - R) / bin_width
    return float(dens.mean() * 2 * np.pi * R), float(arcs.std() / arcs.mean()), offset


@pytest.mark.slow
def test_compensation_warns_below_the_resolution_it_needs():
    """With the paper's 512 bins, 256² makes pixels 2.5 bins wide: compensate warns, naming
    the size given and the size needed (427: MAX_PIXEL_BINS = 1.5), and the surface is
    indeed off there (half a bin out, low and uneven). At 427² and 512² it does not warn,
    and the line density over ±2 bins holds ⟨h⟩ · 2πR and is even around the circle."""
    from meshladar.errors import MeshladarWarning
    from meshladar.reconstruct.compensation import MAX_PIXEL_BINS, needed_size

    m = paper._diffuse(0.99)
    sino = ml.simulate(Scene([Disk((0.0, 0.0), R, m)]), Ladar.paper())
    bw = float(np.diff(sino.bin_edges)[0])
    need = needed_size(sino, 1.0)
    assert need == math.ceil(2.0 / (MAX_PIXEL_BINS * bw)) == 427
    expected = _mean_weight(m) * 2 * np.pi * R
    for size, (level, spread, offset) in STATED_BAND.items():
        if size < need:
            with pytest.warns(MeshladarWarning, match=r"size=256 .*2\.50 range bins.*size=427"):
                img = compensate(sino, m, size=size, extent=1.0)
        else:
            img = compensate(sino, m, size=size, extent=1.0)   # warnings are errors here
        got = _band_stats(img, bw)
        assert abs(got[0] / expected - level) < BAND_LEVEL_TOL, (size, got)
        assert abs(got[1] - spread) < BAND_SPREAD_TOL, (size, got)
        assert abs(got[2] - offset) < OFFSET_TOL, (size, got)
