"""Views 180° apart backprojected as one (meshladar.reconstruct._folded) against each view
backprojected on its own: the plain compiled loop, and numpy's sampling written out."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
import meshladar.reconstruct._folded as folded_module
from meshladar import phantoms
from meshladar.reconstruct._folded import (_folded_profiles, backproject_folded,
                                           backproject_views, opposite_pairs)
from meshladar.reconstruct._kernels import backproject

from test_kernels import _interp

#: The folded image against the unfolded one, over the latter's largest |value|: the same
#: sum to rounding, added in another order (measured: 2e-13 at most on these grids).
FOLD_RTOL = 1e-12


def _both(q, angles, w, r0, inv_dr, x, y):
    """(folded image, pairs folded, image of every view on its own)."""
    phi = np.deg2rad(angles)
    plain = np.zeros((y.size, x.size))
    backproject(q, np.cos(phi), np.sin(phi), w, r0, inv_dr, x, y, False, plain)
    out = np.zeros((y.size, x.size))
    pairs = backproject_views(q, angles, w, r0, inv_dr, x, y, False, out)
    return out, pairs, plain


# m = −2 r0 / Δr: n − 1 (bins symmetric about 0), n (scikit-image's grid: centres k − n/2),
# n − 3 and n + 2 (a few bins covered by one view only)
@pytest.mark.parametrize("m_less_n", [-1, 0, -3, 2])
def test_folded_pairs_equal_each_view_on_its_own(m_less_n):
    # every 1°, so views at 0°, 90°, 180°, 270° put pixels exactly on bin centres and on the
    # profiles' last samples (pixel centres = bin centres at 0°: n = size)
    rng = np.random.default_rng(3)
    n = 64
    angles = np.arange(360.0)
    q = rng.normal(size=(360, n))
    w = np.full(360, np.pi / 360)
    inv_dr = n / 2.0
    r0 = -(n + m_less_n) / 2.0 / inv_dr
    x = (np.arange(n) - n / 2 + 0.5) * 2.0 / n
    out, pairs, plain = _both(q, angles, w, r0, inv_dr, x, x)
    assert pairs == 180
    assert np.abs(out - plain).max() <= FOLD_RTOL * np.abs(plain).max()
    # numpy's sampling at random angles, where no pixel sits on a sample's edge
    angles = np.concatenate([a := rng.uniform(0, 180, 40), a + 180.0])
    q = rng.normal(size=(80, n))
    y = np.linspace(-1.1, 0.9, 23)
    out, pairs, _ = _both(q, angles, w[:80], r0, inv_dr, x, y)
    X, Y = np.meshgrid(x, y)
    phi = np.deg2rad(angles)
    want = sum(w[v] * _interp(q[v], (-(X * np.cos(phi[v]) + Y * np.sin(phi[v])) - r0) * inv_dr,
                              False) for v in range(80))
    assert pairs == 40
    np.testing.assert_allclose(out, want, rtol=0, atol=FOLD_RTOL * np.abs(want).max())


def test_unpaired_repeated_and_unequal_views():
    rng = np.random.default_rng(4)
    n = 50
    angles = np.concatenate([np.arange(0.0, 360.0, 2.0), [4.0, 184.0, 184.0, 7.5, 91.25]])
    q = rng.normal(size=(angles.size, n))
    w = rng.uniform(0.5, 2.0, angles.size)
    x = np.linspace(-1.3, 1.2, 41)
    out, pairs, plain = _both(q, angles, w, -1.0, n / 2.0, x, x[::-1].copy() * 0.9)
    # 90 pairs of the 2° views, and 4° with one of the two 184°: the other 184°, 7.5° and
    # 91.25° are backprojected on their own
    assert pairs == 91
    assert np.abs(out - plain).max() <= FOLD_RTOL * np.abs(plain).max()


def test_one_bin_and_a_view_of_weight_zero():
    # one bin at r = 0: the profile is its one sample at u = 0 exactly, nothing between
    # samples to fold; a pair whose first view weighs 0 is backprojected view by view
    x = np.array([-0.5, 0.0, 0.5])
    angles = np.array([0.0, 180.0, 30.0, 210.0])
    q = np.array([[2.0], [3.0], [5.0], [7.0]])
    out, pairs, plain = _both(q, angles, np.array([1.0, 1.0, 0.0, 0.5]), 0.0, 4.0, x, x)
    assert pairs == 1
    assert np.abs(out - plain).max() <= FOLD_RTOL * np.abs(plain).max()
    assert out[1, 1] == 2.0 + 3.0 + 0.5 * 7.0                # the centre pixel is on it


def test_rows_beyond_float64_take_each_view_pixel_by_pixel():
    # u overflows to ±inf at the outer columns: such pixels lie beyond FOLD_REACH, so
    # backproject_views leaves every view to the plain loop; the folded kernel called on
    # them directly samples those rows view by view with the bounds tested per pixel
    rng = np.random.default_rng(6)
    n = 16
    angles = np.array([10.0, 190.0, 100.0, 280.0])
    q = rng.normal(size=(4, n))
    w = np.full(4, 0.5)
    x = np.array([-1e305, -0.5, 0.0, 0.25, 1e305])
    r0, inv_dr = -(n - 1) / 2e5, 1e5
    out, pairs, plain = _both(q, angles, w, r0, inv_dr, x, x)
    assert pairs == 0
    np.testing.assert_array_equal(out, plain)
    phi = np.deg2rad(angles)
    a, b, folded, m = _folded_profiles(q, angles, np.cos(phi), np.sin(phi), w, n - 1)
    assert a.size == 2
    direct = np.zeros((5, 5))
    backproject_folded(q, folded, a, b, m, np.cos(phi), np.sin(phi), w, r0, inv_dr, x, x,
                       direct)
    assert np.all(np.isfinite(direct))
    assert np.abs(direct - plain).max() <= FOLD_RTOL * np.abs(plain).max()


def test_what_is_not_folded_goes_view_by_view():
    # each case leaves pairs to the plain loop, so the image is its image bit for bit
    rng = np.random.default_rng(8)
    n = 32
    angles = np.arange(0.0, 360.0, 5.0)
    q = rng.normal(size=(angles.size, n))
    w = np.full(angles.size, 0.1)
    x = np.linspace(-1.0, 1.0, 21)
    inv_dr = n / 2.0
    r0 = -(n - 1) / 2.0 / inv_dr
    cases = {
        # angles made by repeated addition: 180° apart only to ~1e-13°, directions opposite
        # to more than FOLD_TOL
        "summed angles": (q, np.cumsum(np.full(72, 5.0000000000001)) - 5.0, x, r0, False),
        "x decreasing": (q, angles, x[::-1].copy(), r0, False),
        "no bins": (q[:, :0], angles, x, r0, False),
        "far pixels": (q, angles, x * 1e6, r0, False),
        "m = n - 0.4, not a whole bin": (q, angles, x, r0 + 0.3 / inv_dr, False),
        "m = 3n, mostly one view's bins": (q, angles, x, -3.0, False),
        "nearest samples": (q, angles, x, r0, True),
    }
    for name, (qq, aa, xx, rr, nearest) in cases.items():
        phi = np.deg2rad(aa)
        plain = np.zeros((21, xx.size))
        backproject(qq, np.cos(phi), np.sin(phi), w, rr, inv_dr, xx, x, nearest, plain)
        out = np.zeros((21, xx.size))
        assert backproject_views(qq, aa, w, rr, inv_dr, xx, x, nearest, out) == 0, name
        np.testing.assert_array_equal(out, plain, err_msg=name)
    # a NaN in one view, or weights whose ratio overflows: that pair alone goes view by view
    # (NaN where the plain loop puts it), the other 35 are folded
    bad_q = q.copy()
    bad_q[37, 5] = np.nan                                  # 185°, partner of 5°
    bad_w = w.copy()
    bad_w[[2, 38]] = 1e-310, 1.0                           # 10° and 190°
    phi = np.deg2rad(angles)
    plain = np.zeros((21, 21))
    backproject(bad_q, np.cos(phi), np.sin(phi), bad_w, r0, inv_dr, x, x, False, plain)
    out = np.zeros((21, 21))
    assert backproject_views(bad_q, angles, bad_w, r0, inv_dr, x, x, False, out) == 34
    np.testing.assert_array_equal(np.isnan(out), np.isnan(plain))
    assert np.isnan(plain).any()
    ok = ~np.isnan(plain)
    assert np.abs(out - plain)[ok].max() <= FOLD_RTOL * np.abs(plain[ok]).max()


def test_opposite_pairs_match_directions():
    angles = np.array([0.0, 180.0, 359.9999999999, 179.9999999999, 90.0, 270.0, 45.0])
    phi = np.deg2rad(angles)
    a, b = opposite_pairs(angles, np.cos(phi), np.sin(phi))
    assert sorted(zip(a.tolist(), b.tolist())) == [(0, 1), (2, 3), (4, 5)]


def test_fbp_folds_and_equals_the_unfolded_image(monkeypatch):
    disk = phantoms.load("disk")
    sino = ml.simulate(disk.scene, disk.ladar)
    calls = []
    real = folded_module.backproject_folded

    def counting(q, f, a, *args):
        calls.append(a.size)
        return real(q, f, a, *args)

    monkeypatch.setattr(folded_module, "backproject_folded", counting)
    image = ml.fbp(sino, size=128)
    assert calls == [180]
    monkeypatch.setattr(folded_module, "FOLD_TOL", -1.0)        # no pair qualifies
    unfolded = ml.fbp(sino, size=128)
    assert calls == [180]
    assert np.abs(image.values - unfolded.values).max() <= FOLD_RTOL * np.abs(unfolded.values).max()
