"""Filtered backprojection: normalisation, orientation, the scikit-image peer, preprocessing."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import MeshladarWarning, ParameterError
from meshladar.reconstruct import FILTERS, fourier_filter, resample_uniform

skimage_radon = pytest.importorskip("skimage.transform")


def disk_radon_sinogram(center, radius, n_bins, extent, angles_deg, value=1.0):
    """Exact bin integrals of the Radon transform of a uniform disk (2 sqrt(R² − s²))."""
    edges = np.linspace(-extent, extent, n_bins + 1)
    phi = np.deg2rad(angles_deg)

    def prim(s):                                    # ∫ 2 sqrt(R² − s²) ds
        s = np.clip(s, -radius, radius)
        return s * np.sqrt(radius**2 - s**2) + radius**2 * np.arcsin(s / radius)

    rc = -(center[0] * np.cos(phi) + center[1] * np.sin(phi))
    vals = value * (prim(edges[None, 1:] - rc[:, None]) - prim(edges[None, :-1] - rc[:, None]))
    return ml.Sinogram(vals, angles_deg=angles_deg, bin_edges=edges)


#: a uniform disk of value 1 reconstructs to 1 inside: the measured mean is within 1e-5 at
#: 256 bins and 360 views; away from the rim (r < 0.8 R) the ripple is ~1e-4.
DISK_MEAN_TOL = 1e-3
DISK_RIPPLE_TOL = 5e-3
#: streaks outside the disk (r > 1.2 R) from 360 discrete views: measured ≤ 0.02
OUTSIDE_TOL = 0.05


@pytest.mark.parametrize("center", [(0.0, 0.0), (0.3, -0.2), (-0.45, 0.35)])
def test_uniform_disk_reconstructs_to_one_at_its_true_position(center):
    R = 0.3
    sino = disk_radon_sinogram(center, R, 256, 1.0, np.arange(360.0))
    image = ml.fbp(sino, size=200, extent=1.0)
    X, Y = np.meshgrid(image.x, image.y)
    rr = np.hypot(X - center[0], Y - center[1])
    inside = image.values[rr < 0.8 * R]
    assert abs(inside.mean() - 1.0) < DISK_MEAN_TOL
    assert np.max(np.abs(inside - 1.0)) < DISK_RIPPLE_TOL
    assert np.max(np.abs(image.values[(rr > 1.2 * R) & (np.hypot(X, Y) < 1.0)])) < OUTSIDE_TOL
    # orientation: image[i, j] is the value at (x_j, y_i); not mirrored in x or y
    assert image.sample(np.array(center)) == pytest.approx(1.0, abs=DISK_RIPPLE_TOL)
    if center != (0.0, 0.0):
        for mirrored in ((-center[0], center[1]), (center[0], -center[1])):
            assert abs(image.sample(np.array(mirrored))) < OUTSIDE_TOL


@pytest.mark.parametrize("filter", FILTERS)
def test_matches_scikit_image_iradon(filter):
    # the same discretisation: unit bins centred on k − n/2, views 180° − φ, pixel centres on
    # skimage's grid; a phantom sinogram (zero at its ends, so no edge-sample ambiguity)
    n = 128
    pair = ml.phantoms.load("disk_pair", materials={"small": "aluminum"})
    edges = (np.arange(n + 1) - n / 2 - 0.5) * (2.0 / n)
    sino = ml.simulate(pair.scene, ml.Ladar(np.arange(360.0), edges))
    bw = 2.0 / n
    ours = ml.fbp(sino, size=n, extent=1.0, center=(-0.5 * bw, -0.5 * bw), filter=filter)
    theirs = skimage_radon.iradon((sino.values / bw**2).T, theta=180.0 - sino.angles_deg,
                                  filter_name=filter, interpolation="linear", circle=False,
                                  output_size=n)
    # Identical arithmetic up to summation order, except where a pixel's range falls exactly
    # on the last sample: there cos(180° − φ) vs −cos φ rounding decides between the sample
    # and iradon's zero beyond it (corner pixels at 0°/90°/...; measured 1e-5 of the max).
    # The bound is 1e-3 of the image maximum.
    diff = np.abs(ours.values - theirs)
    assert np.max(diff) <= 1e-4 * np.max(np.abs(theirs))
    assert np.median(diff) <= 1e-12 * np.max(np.abs(theirs))


def test_nearest_interpolation_is_close_to_linear_on_smooth_data():
    sino = disk_radon_sinogram((0.1, 0.0), 0.4, 256, 1.0, np.arange(360.0))
    lin = ml.fbp(sino, size=128, extent=1.0)
    near = ml.fbp(sino, size=128, extent=1.0, interpolation="nearest")
    X, Y = np.meshgrid(lin.x, lin.y)
    inside = np.hypot(X - 0.1, Y) < 0.3
    assert np.max(np.abs(near.values[inside] - 1.0)) < 0.02
    assert lin.info["interpolation"] == "linear" and near.info["interpolation"] == "nearest"


def test_ramp_filter_is_abs_frequency():
    r = fourier_filter(1024, "ramp")
    nu = np.fft.fftfreq(1024)
    low = np.abs(nu) < 0.4
    np.testing.assert_allclose(r[low][1:], np.abs(nu[low])[1:], rtol=0.02, atol=2e-4)
    # windows only attenuate, most at Nyquist (shepp-logan least: sinc(1/2) = 2/π)
    for f in FILTERS[1:]:
        w = fourier_filter(1024, f)
        assert np.all(w <= r + 1e-12) and w[512] <= 2 / math.pi * r[512] + 1e-12


def test_lambertian_disk_from_analytic_model_is_a_clean_ring():
    disk = ml.phantoms.load("disk")
    image = ml.fbp(ml.simulate(disk.scene, disk.ladar), size=256, extent=1.0)
    radii = np.linspace(0.0, 1.0, 201)
    prof = image.radial_profile(radii)
    peak = radii[np.argmax(prof)]
    assert abs(peak - 0.8) <= 2 * image.pixel_size          # the ring sits on the surface
    # flat interior pedestal, no darkening toward the rim (paper Sec. 3: a Lambertian surface
    # reconstructs perfectly): the band just inside equals the deeper interior to 1% of peak
    deep = prof[(radii > 0.3) & (radii < 0.6)].mean()
    band = prof[(radii > 0.72) & (radii < 0.776)].mean()
    assert abs(band - deep) < 0.01 * prof.max()


def test_nonuniform_bins_are_resampled_conserving_integrals():
    sino = disk_radon_sinogram((0.0, 0.1), 0.4, 256, 1.0, np.arange(0.0, 360.0, 2.0))
    rng = np.random.default_rng(7)
    keep = np.sort(np.concatenate([[0, 256], rng.choice(np.arange(1, 256), 180, replace=False)]))
    coarse = ml.Sinogram(np.add.reduceat(sino.values, keep[:-1], axis=1),
                         angles_deg=sino.angles_deg, bin_edges=sino.bin_edges[keep])
    uni = resample_uniform(coarse)
    np.testing.assert_allclose(uni.total(), coarse.total(), rtol=1e-12)
    image = ml.fbp(coarse, size=96, extent=1.0)
    assert image.info["resampled"]
    X, Y = np.meshgrid(image.x, image.y)
    assert abs(image.values[np.hypot(X, Y - 0.1) < 0.25].mean() - 1.0) < 0.02


def test_partial_angular_coverage_warns():
    sino = disk_radon_sinogram((0.0, 0.0), 0.4, 64, 1.0, np.arange(0.0, 180.0, 2.0))
    with pytest.warns(MeshladarWarning, match="do not cover the full circle"):
        ml.fbp(sino, size=32, extent=1.0)


@pytest.mark.parametrize("scale", [1e-300, 1e300, 2.0**1020])
def test_any_magnitude_of_values_reconstructs_to_the_scaled_image(scale):
    # values of 1e307 once gave a NaN image (the filter overflowed); filtering runs at unit
    # scale, so the image scales exactly with the data up to float64's range
    sino = disk_radon_sinogram((0.1, 0.0), 0.5, 64, 1.0, np.arange(0.0, 360.0, 3.0))
    ref = ml.fbp(sino, size=48, extent=1.0).values
    big = ml.Sinogram(sino.values * scale, angles_deg=sino.angles_deg,
                      bin_edges=sino.bin_edges)
    got = ml.fbp(big, size=48, extent=1.0).values
    assert np.all(np.isfinite(got))
    # same operations on values a power of two apart, then one product: round-off only
    np.testing.assert_allclose(got / scale, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_an_image_beyond_float64_is_refused():
    # bin integrals of 1e300 in bins 3e-12 wide: a Radon transform of 3e311
    sino = disk_radon_sinogram((0.0, 0.0), 5e-11, 64, 1e-10, np.arange(0.0, 360.0, 3.0))
    huge = ml.Sinogram(sino.values / sino.values.max() * 1e300, angles_deg=sino.angles_deg,
                       bin_edges=sino.bin_edges)
    with pytest.raises(ParameterError, match=r"sinogram: values up to 1e\+300 in bins 3.13e-12 "
                                             r"wide give an image beyond float64's range"):
        ml.fbp(huge, size=16, extent=1e-10)


def test_views_too_few_for_the_bins_warn_with_the_number_needed():
    disk = ml.phantoms.load("disk")
    fine = ml.Ladar.centered(n_bins=1024, bin_width=2.4 / 1024, angles_deg=np.arange(0, 360, 8.0))
    with pytest.warns(MeshladarWarning, match=r"45 views are too few for the 34\d bins across "
                                              r"the target's returns: FBP samples the angles "
                                              r"fully with about 5\d\d"):
        ml.fbp(ml.simulate(disk.scene, fine), size=64, extent=1.2)
    # the paper's own sampling (350 bins across, 360 views) reconstructs without a word
    paper = ml.simulate(disk.scene, disk.ladar)
    ml.fbp(paper, size=64, extent=1.0)                    # filterwarnings = error


def test_view_weights_follow_uneven_spacing():
    # two half-circles sampled at different densities still give the uniform disk
    angles = np.concatenate([np.arange(0.0, 180.0, 0.5), np.arange(180.0, 360.0, 1.0)])
    sino = disk_radon_sinogram((0.0, 0.0), 0.4, 256, 1.0, angles)
    image = ml.fbp(sino, size=128, extent=1.0)
    X, Y = np.meshgrid(image.x, image.y)
    assert abs(image.values[np.hypot(X, Y) < 0.3].mean() - 1.0) < DISK_MEAN_TOL


@pytest.mark.parametrize("kwargs, match", [
    (dict(size=0), r"size must be an integer >= 1; got 0"),
    (dict(size=2.5), r"size must be an integer >= 1; got 2.5"),
    (dict(extent=-1.0), r"extent must be in \[1e-150, 1e\+300\]; got -1.0"),
    (dict(filter="rampp"), r"filter must be one of \('ramp', 'shepp-logan', 'cosine', "
                           r"'hamming', 'hann'\); got 'rampp'"),
    (dict(interpolation="cubic"), r"interpolation must be one of \('linear', 'nearest'\)"),
    (dict(center=(0.0,)), r"center must be a point"),
])
def test_bad_fbp_arguments(kwargs, match):
    sino = disk_radon_sinogram((0.0, 0.0), 0.4, 32, 1.0, np.arange(0.0, 360.0, 10.0))
    with pytest.raises(ParameterError, match=match):
        ml.fbp(sino, **kwargs)
    with pytest.raises(ParameterError, match="sinogram must be a meshladar.Sinogram"):
        ml.fbp(sino.values)


def test_log_and_clip_preprocessing():
    v = np.array([[0.0, 1e-9, 1e-3, 1.0, 100.0]])
    sino = ml.Sinogram(v, angles_deg=[0.0], bin_edges=np.arange(6.0))
    lg = ml.log_radiance(sino, floor=1e-6)
    m = 1e-6 * 100.0
    np.testing.assert_allclose(lg.values, [[0.0, 0.0, math.log(1e-3 / m), math.log(1 / m),
                                            math.log(100 / m)]])
    assert lg.info["preprocess"] == "log(floor=1e-06)"
    cl = ml.clip_radiance(sino, threshold=0.008)
    np.testing.assert_allclose(cl.values, [[0.0, 1e-9, 1e-3, 0.8, 0.8]])
    assert np.all(ml.log_radiance(ml.Sinogram(np.zeros((1, 2)), angles_deg=[0.0],
                                              bin_edges=[0, 1, 2])).values == 0)
    with pytest.raises(ParameterError, match=r"floor must be in \(0, 1\]"):
        ml.log_radiance(sino, floor=0.0)
    with pytest.raises(ParameterError, match=r"threshold must be in \(0, 1\]"):
        ml.clip_radiance(sino, threshold=2.0)


def test_image_grid_contract():
    sino = disk_radon_sinogram((0.0, 0.0), 0.4, 32, 1.0, np.arange(0.0, 360.0, 10.0))
    for size in (7, 8):                                  # odd and even
        img = ml.fbp(sino, size=size, extent=2.0, center=(1.0, -1.0))
        h = 4.0 / size
        np.testing.assert_allclose(img.x, 1.0 - 2.0 + (np.arange(size) + 0.5) * h)
        np.testing.assert_allclose(img.y, -1.0 - 2.0 + (np.arange(size) + 0.5) * h)
        assert img[0, 0] == img.values[0, 0] and np.asarray(img).shape == (size, size)
        assert not img.values.flags.writeable


# ------------------------------------------------------------------ the default frame

#: the ring of a Lambertian disk reconstructed from its exact profiles peaks at its radius
#: within a bin and a pixel (measured within 0.6 bins at 256²)
RING_PEAK_TOL_BINS = 1.0
#: the ring's integral across ±5 bins, on every ray from the centre, against its mean over
#: the rays: measured 0.86 at the least (a cropped ring gives 0 where it is cut)
RING_PRESENT = 0.5


def test_a_part_in_millimetres_reconstructs_uncropped_by_default():
    """A disk of radius 50 mm at (30, −20) mm: ``fbp``'s default square is the bins' reach
    about the origin, |C| + R (the analytic bins' closed form), so the whole ring is in the
    image, peaking at R all round (the old default, [−1, 1]², held none of it)."""
    R, C = 50.0, np.array([30.0, -20.0])
    scene = ml.Scene([ml.Disk(tuple(C), R, ml.materials.lambertian(0.5))])
    ladar = ml.Ladar.covering(scene, n_bins=256)
    sino = ml.simulate(scene, ladar)
    image = ml.fbp(sino, size=256)
    reach = math.hypot(*C) + R
    assert image.extent == pytest.approx(reach, rel=1e-12)
    assert round(image.extent, 2) == 86.06 and image.center == (0.0, 0.0)   # the README's
    # the ring is in the image all round: on each of 36 rays from C, its brightest radius
    # is R and its integral across ±5 bins is there
    dr = ladar.bin_edges[1] - ladar.bin_edges[0]
    radii = np.linspace(R - 5 * dr, R + 5 * dr, 201)
    angles = np.deg2rad(np.arange(0.0, 360.0, 10.0))
    rays = C + radii[:, None, None] * np.stack([np.cos(angles), np.sin(angles)], -1)[None]
    profile = image.sample(rays)                              # (radii, angles)
    peaks = radii[np.argmax(profile, axis=0)]
    assert np.all(np.abs(peaks - R) <= RING_PEAK_TOL_BINS * dr + image.pixel_size), peaks
    band = np.trapezoid(profile, radii, axis=0)
    assert band.min() > RING_PRESENT * band.mean(), band / band.mean()
    # the default is the bins' reach, the command line's default too
    # (tests/cli/test_reconstruct_cli.py)
    from meshladar.reconstruct.fbp2d import bins_reach
    assert bins_reach(sino) == image.extent
    np.testing.assert_array_equal(image.values, ml.fbp(sino, size=256, extent=reach).values)
