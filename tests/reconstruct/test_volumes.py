"""3-D reflective tomography (meshladar.reconstruct.volumes): the 3-D Radon inversion's
normalisation on a uniform ball, a Lambertian sphere's shell, and stacked 2-D slices."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import lambertian
from meshladar.meshes import fibonacci_sphere
from meshladar.forward.resolved import resolve
from meshladar.errors import MeshladarWarning
from meshladar.images import Volume
from meshladar.reconstruct.volumes import (fbp3d, fbp_slices, sphere_weights,
                                           UNDERSAMPLED_FACTOR, views_needed)

#: the ball's interior: −g'' is exactly 2π on every bin inside, so the reconstruction is 1
#: to rounding (measured 1.0000); the quadrature over 400 Fibonacci directions decides the
#: rest
BALL_RTOL = 1e-3
#: outside the ball the views' contributions cancel only as well as the direction
#: quadrature does (measured at most 3.3e-3 beyond 1.15 a)
BALL_OUTSIDE = 1e-2


def _ball_sinogram(a, n_views=400, n_bins=128):
    """Exact bin integrals of a uniform ball's 3-D Radon transform g(s) = π (a² − s²)."""
    W = fibonacci_sphere(n_views)
    edges = np.linspace(-1.0, 1.0, n_bins + 1)
    lo, hi = np.clip(edges[:-1], -a, a), np.clip(edges[1:], -a, a)

    def prim(s):
        return math.pi * (a * a * s - s ** 3 / 3)

    vals = np.broadcast_to(prim(hi) - prim(lo), (n_views, n_bins))
    return ml.Sinogram(vals, angles_deg=np.degrees(np.arctan2(W[:, 1], W[:, 0])),
                       bin_edges=edges, view_vectors=W)


@pytest.mark.slow
def test_uniform_ball_inverts_to_the_ball():
    a = 0.6
    vol = fbp3d(_ball_sinogram(a), size=96, extent=1.0)
    inside = vol.radial_profile(np.linspace(0.0, 0.9 * a, 10))
    np.testing.assert_allclose(inside, 1.0, rtol=BALL_RTOL)
    outside = vol.radial_profile(np.linspace(1.15 * a, 1.5 * a, 8))
    assert np.all(np.abs(outside) < BALL_OUTSIDE), outside
    # the centre voxel and an off-centre one, sampled directly
    np.testing.assert_allclose(vol.sample([[0.0, 0.0, 0.0], [0.2, -0.1, 0.15]]), 1.0,
                               rtol=BALL_RTOL)
    assert vol.info["method"] == "fbp3d" and vol.shape == (96, 96, 96)


@pytest.mark.slow
def test_lambertian_sphere_shell_peaks_at_its_radius():
    """A Lambertian sphere's range profiles from 200 Fibonacci views: the reconstruction's
    spherical mean peaks at R (within one voxel) and is far smaller away from the shell."""
    trimesh = pytest.importorskip("trimesh")
    R = 0.5
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=5, radius=R),
                               material=lambertian(0.5))
    ladar = ml.Ladar(None, np.linspace(-1.0, 1.0, 97), view_vectors=fibonacci_sphere(200))
    vol = fbp3d(ml.simulate(scene, ladar, model="mesh", normals="smooth"), size=96,
                  extent=1.0)
    r = np.linspace(0.0, 0.8, 161)
    prof = vol.radial_profile(r)
    voxel = 2.0 / 96
    assert abs(r[np.argmax(prof)] - R) <= voxel
    assert prof.max() > 5 * np.abs(prof[(r > 0.7)]).max()


@pytest.mark.slow
def test_fbp_slices_of_a_cylinder_matches_the_2d_disk():
    """A Lambertian cylinder seen from views about its axis, resolved in elevation and range:
    each slice (per unit height) is the 2-D reconstruction of the disk, here compared with
    the exact analytic disk's FBP (faceting and sampling: measured 2.4% relative L2)."""
    trimesh = pytest.importorskip("trimesh")
    R, H = 0.5, 1.0
    cyl = trimesh.creation.cylinder(radius=R, height=H, sections=1024)
    scene = ml.Scene.from_mesh(cyl, material=lambertian(0.5))
    ladar = ml.Ladar(np.arange(0.0, 360.0, 2.0), np.linspace(-0.64, 0.64, 129))
    ret = resolve(scene, ladar, [("elevation", np.linspace(-0.3, 0.3, 4)),
                                 ("range", ladar.bin_edges)], rays_per_bin=4)
    vol = fbp_slices(ret, size=128, extent=0.64)
    assert vol.shape == (3, 128, 128)
    np.testing.assert_allclose(vol.z, [-0.2, 0.0, 0.2], atol=1e-15)
    disk = ml.fbp(ml.simulate(ml.Scene([ml.Disk((0.0, 0.0), R, lambertian(0.5))]), ladar),
                  size=128, extent=0.64)
    for k in range(3):
        err = np.linalg.norm(vol.values[k] - disk.values) / np.linalg.norm(disk.values)
        assert err < 0.06, (k, err)


def test_sphere_weights_share_the_sphere():
    from meshladar.reconstruct.volumes import coverage_gap_deg

    # the largest unseen angle: ~10.6° for 200 Fibonacci views, 90° for a hemisphere
    assert coverage_gap_deg(fibonacci_sphere(200)) < 12.0
    assert abs(coverage_gap_deg(fibonacci_sphere(400, hemisphere=True)) - 90.0) < 1.0
    w = sphere_weights(fibonacci_sphere(300))
    np.testing.assert_allclose(w.sum(), 4 * math.pi, rtol=1e-12)
    np.testing.assert_allclose(w, 4 * math.pi / 300, rtol=0.1)
    # the six axis directions: a cube's faces, 4π/6 each by symmetry (the 2e5-point
    # estimate of each cell: within 1%)
    w = sphere_weights(np.vstack([np.eye(3), -np.eye(3)]))
    np.testing.assert_allclose(w, 4 * math.pi / 6, rtol=1e-2)
    # two views: a hemisphere each
    np.testing.assert_allclose(sphere_weights([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]),
                               2 * math.pi, rtol=1e-2)


def test_too_few_views_over_the_sphere_warn():
    """A ball of radius 0.6 in 1/64 bins spans N = 78 bins: fully sampled by π N²/4 = 4779
    views (128 bins across: 12,868; a smoothing of 2 bins halves N); fbp3d warns below
    1/16 of them (299: the spacing 4 times the full sampling's, as 2-D fbp) and not
    above."""
    assert views_needed(78) == math.ceil(math.pi * 78 ** 2 / 4) == 4779
    assert views_needed(128) == 12868 and views_needed(128, smooth=2.0) == views_needed(64)
    assert views_needed(78, smooth=0.5) == views_needed(78)
    assert views_needed(78) / UNDERSAMPLED_FACTOR == pytest.approx(298.7, abs=0.1)
    with pytest.warns(ml.errors.MeshladarWarning,
                      match="250 views are too few over the sphere for the 78 bins.*4779"):
        fbp3d(_ball_sinogram(0.6, n_views=250), size=8, extent=1.0)
    fbp3d(_ball_sinogram(0.6, n_views=350), size=8, extent=1.0)     # no warning (errors)
    # smoothing by 1.5 bins: N = 52 effective, 2124 needed, warned below 133
    fbp3d(_ball_sinogram(0.6, n_views=250), size=8, extent=1.0, smooth=1.5)
    with pytest.warns(ml.errors.MeshladarWarning, match="120 views are too few"):
        fbp3d(_ball_sinogram(0.6, n_views=120), size=8, extent=1.0, smooth=1.5)


def test_volume_checks():
    sino = _ball_sinogram(0.5, n_views=60, n_bins=16)
    with pytest.raises(ml.errors.ParameterError, match="weights"):
        fbp3d(sino, size=8, weights=np.ones(3))
    uneven = ml.Sinogram(sino.values[:, :3], angles_deg=sino.angles_deg,
                         bin_edges=[0.0, 0.1, 0.3, 0.4], view_vectors=sino.view_vectors)
    with pytest.raises(ml.errors.ParameterError, match="uniform range bins"):
        fbp3d(uneven, size=8)
    with pytest.raises(ml.errors.ParameterError, match="size"):
        fbp3d(sino, size=0)
    with pytest.raises(ml.errors.ParameterError, match="values"):
        Volume(np.zeros((2, 2)), x=[0, 1], y=[0, 1], z=[0])
    # views that do not cover the sphere: a hemisphere, a plane of views (a 2-D sinogram)
    hemi = fibonacci_sphere(300, hemisphere=True)
    half = ml.Sinogram(np.ones((300, 16)),
                       bin_edges=np.linspace(-1, 1, 17), view_vectors=hemi)
    with pytest.raises(ml.errors.ParameterError, match="whole sphere"):
        fbp3d(half, size=8)
    flat = ml.Sinogram(np.ones((36, 16)), angles_deg=np.arange(0.0, 360.0, 10.0),
                       bin_edges=np.linspace(-1, 1, 17))
    with pytest.raises(ml.errors.ParameterError, match="whole sphere"):
        fbp3d(flat, size=8)


#: a part of curved surfaces, 600 Fibonacci views, 64³: the iso-surface lies within this
#: many voxels of the part's surface and covers it (measured means 1.4 and 1.0 voxels,
#: 95th percentiles 2.0 and 1.4)
SHAPE_MEAN_VOXELS = 2.0
SHAPE_P95_VOXELS = 3.0


@pytest.mark.slow
def test_a_cad_part_reconstructs_to_its_shape():
    """A capsule through a torus: 600 views over the sphere, received power, 3-D Radon
    inversion; the default iso-surface (half the 99.9th percentile) lies on the part's
    surface and covers all of it. (The angular sampling sets the sharpness: a volume n
    voxels across needs ~4π(n/2)² / (2σ)² views for a smoothing of σ bins; with fewer views
    the planes of sharp returns stay uncancelled.)"""
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("pyvista")
    from scipy.spatial import cKDTree

    from meshladar.viz import viewer

    cap = trimesh.creation.capsule(height=0.6, radius=0.15, count=[32, 32])
    cap.apply_translation((0, 0, -0.3))
    tor = trimesh.creation.torus(major_radius=0.35, minor_radius=0.08, major_sections=96,
                                 minor_sections=32)
    tor.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
    tor.apply_translation((0, 0, 0.25))
    part = trimesh.util.concatenate([cap, tor])
    scene = ml.Scene.from_mesh(part, material=lambertian(0.5))
    ladar = ml.Ladar(None, np.linspace(-0.8, 0.8, 65), view_vectors=fibonacci_sphere(600))
    sino = ml.simulate(scene, ladar, model="mesh", radiometry="power", normals="smooth")
    vol = fbp3d(sino, size=64, extent=0.8, smooth=1.5)
    surf = np.asarray(viewer.volume_surface(vol).points)
    truth, _ = trimesh.sample.sample_surface_even(part, 50_000, seed=0)
    voxel = 1.6 / 64
    off, _ = cKDTree(truth).query(surf)            # iso-surface -> part
    gap, _ = cKDTree(surf).query(truth)            # part -> iso-surface
    for d in (off, gap):
        assert d.mean() < SHAPE_MEAN_VOXELS * voxel
        assert np.percentile(d, 95) < SHAPE_P95_VOXELS * voxel


def test_reconstruct_command_inverts_3d_views(tmp_path):
    """`meshladar reconstruct` on a sinogram of views over the sphere runs the 3-D Radon
    inversion: three central slices as the figure, the volume in OUTPUT.volume.npz."""
    pytest.importorskip("matplotlib")
    from meshladar.cli import main

    path = tmp_path / "ball.npz"
    ml.io.save_sinogram(path, _ball_sinogram(0.6, n_views=200, n_bins=64))
    out = tmp_path / "ball.png"
    assert main(["reconstruct", str(path), "-o", str(out), "--size", "48", "--extent", "1.0",
                 "--quiet"]) == 0
    arrays, meta = ml.io.load_result(tmp_path / "ball.volume.npz")
    assert meta["kind"] == "volume" and arrays["values"].shape == (48, 48, 48)
    vol = Volume(arrays["values"], x=arrays["x"], y=arrays["y"], z=arrays["z"])
    np.testing.assert_allclose(vol.radial_profile([0.0, 0.2, 0.4]), 1.0, rtol=BALL_RTOL)
    assert out.stat().st_size > 10_000
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "f.png"), "--filter",
                 "hann"]) == 2
    # the figure is Volume.plot's: three slices on one scale symmetric about zero, log
    # input labelled, nothing overlapping
    from meshladar.viz import style

    logged = fbp3d(ml.log_radiance(_ball_sinogram(0.6, n_views=200, n_bins=64)),
                        size=32, extent=1.0)
    assert logged.info["preprocess"].startswith("log") and "input='log" in repr(logged)
    fig = logged.plot()
    panels = [ax for ax in fig.axes if ax.images]
    assert len(panels) == 3 and len({id(ax.images[0].norm) for ax in panels}) == 1
    norm = panels[0].images[0].norm
    assert norm.vmin == -norm.vmax
    assert any("reconstruction of log input" in ax.get_ylabel() for ax in fig.axes)
    assert style.overlapping_texts(fig) == []


def test_old_names_warn_and_name_the_new_ones():
    """radon3d and fbp_stack are deprecated aliases (one release) of fbp3d and fbp_slices:
    they warn, naming the new function, and return its result."""
    from meshladar.reconstruct import volumes

    sino = _ball_sinogram(0.5, n_views=200, n_bins=32)
    with pytest.warns(DeprecationWarning, match="fbp3d"):
        old = volumes.radon3d(sino, size=8, extent=1.0)
    np.testing.assert_array_equal(old.values, fbp3d(sino, size=8, extent=1.0).values)
    with pytest.warns(DeprecationWarning, match="fbp_slices"):
        with pytest.raises(ml.errors.ParameterError, match="fbp_slices needs Returns"):
            volumes.fbp_stack(sino)


# ------------------------------------------------------------------ the default frame

def _shifted_ball_sinogram(a, centre, n_views, n_bins):
    """Exact bin integrals of a uniform ball of radius a at ``centre``: plane integrals
    π (a² − u²), u = r + c·w the range about the centre, on the bins ``Ladar.covering``
    gives it (the views' ranges ±(|c| + a), half a bin beyond each end)."""
    W = fibonacci_sphere(n_views)
    c = np.asarray(centre, np.float64)
    lo, hi = (W @ -c).min() - a, (W @ -c).max() + a
    dr = (hi - lo) / (n_bins - 1)
    edges = lo - dr / 2 + dr * np.arange(n_bins + 1)
    shift = (W @ c)[:, None]
    u0, u1 = np.clip(edges[:-1] + shift, -a, a), np.clip(edges[1:] + shift, -a, a)

    def prim(u):
        return math.pi * (a * a * u - u ** 3 / 3)

    return ml.Sinogram(prim(u1) - prim(u0), angles_deg=np.degrees(np.arctan2(W[:, 1], W[:, 0])),
                       bin_edges=edges, view_vectors=W)


#: voxels across the ball at half its value, against the closed form 2a / voxel: the edge
#: blurs over a bin and a voxel (measured within 0.5 voxels)
ACROSS_TOL_VOXELS = 2.0


@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (300.0, -200.0, 100.0)])
def test_the_default_cube_holds_a_ball_off_the_origin_at_the_size_its_bins_allow(centre):
    """A ball of radius 50 (mm) from 400 views over the sphere: the default cube is the
    bins' reach about the origin, |c| + a + half a bin, so it holds the ball wherever it is,
    a·size/reach voxels across (closed form, at 64 voxels: 63.3 centred, 7.5 at |c| = 374:
    centre a part before simulating, as ``Ladar.covering`` warns); and the figure's three
    slices cut through the ball's centre, not the cube's."""
    a, c, size = 50.0, np.array(centre), 64
    sino = _shifted_ball_sinogram(a, c, n_views=400, n_bins=96)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshladarWarning)   # 400 views: under-sampled far out
        vol = fbp3d(sino, size=size)
    reach = float(np.max(np.abs(sino.bin_edges)))
    assert vol.info["extent"] == reach
    lo, hi = vol.x[0] - vol.spacing[0] / 2, vol.x[-1] + vol.spacing[0] / 2
    assert lo == pytest.approx(-reach) and hi == pytest.approx(reach)
    assert np.all(c - a >= lo) and np.all(c + a <= hi)                   # contains the ball
    # its size in voxels along the line through its centre
    line = vol.sample(np.stack([vol.x, np.full(size, c[1]), np.full(size, c[2])], -1))
    across = np.count_nonzero(line > 0.5)
    expected = 2 * a / vol.spacing[0]
    assert expected == pytest.approx(63.3 if not c.any() else 7.5, abs=0.05)
    assert abs(across - expected) <= ACROSS_TOL_VOXELS, (across, expected)
    # the figure's slices: through the ball's centre, within a voxel
    from meshladar.viz.quick import target_voxel
    k = target_voxel(vol.values)
    np.testing.assert_allclose([vol.z[k[0]], vol.y[k[1]], vol.x[k[2]]], c[::-1],
                               atol=vol.spacing[0])
