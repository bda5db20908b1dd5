"""The compiled loops of reconstruction (meshladar.reconstruct._kernels) against their numpy
twins on small grids."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.reconstruct._kernels import backproject, backproject3d


def _interp(q, u, nearest):
    """numpy's twin of the kernels' sampling: q at fractional sample u, 0 outside."""
    n = q.size
    if nearest:
        k = np.floor(u + 0.5).astype(int)
        return np.where((k >= 0) & (k < n), q[np.clip(k, 0, n - 1)], 0.0)
    fk = np.floor(u)
    k = fk.astype(int)
    inside = (k >= 0) & (k < n - 1)
    kc = np.clip(k, 0, n - 2)
    lin = q[kc] + (u - fk) * (q[kc + 1] - q[kc])
    last = (k == n - 1) & (u == fk)
    return np.where(inside, lin, np.where(last, q[n - 1], 0.0))


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_matches_numpy(nearest):
    rng = np.random.default_rng(0)
    q = rng.random((7, 20))
    phi = rng.uniform(0, 2 * np.pi, 7)
    w, x, y = rng.random(7), np.linspace(-1, 1, 13), np.linspace(-0.9, 1.1, 11)
    r0, inv_dr = -1.2, 20 / 2.4
    out = np.zeros((11, 13))
    backproject(q, np.cos(phi), np.sin(phi), w, r0, inv_dr, x, y, nearest, out)
    X, Y = np.meshgrid(x, y)
    want = sum(w[v] * _interp(q[v], (-(X * np.cos(phi[v]) + Y * np.sin(phi[v])) - r0) * inv_dr,
                              nearest) for v in range(7))
    np.testing.assert_allclose(out, want, rtol=1e-12, atol=1e-12)


def test_backproject3d_matches_numpy():
    rng = np.random.default_rng(1)
    q = rng.random((5, 16))
    d = rng.normal(size=(5, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    wts = rng.random(5)
    x, y, z = np.linspace(-1, 1, 6), np.linspace(-1, 1, 5), np.linspace(-1, 1, 4)
    r0, inv_dr = -1.5, 15 / 3.0
    out = np.zeros((4, 5, 6))
    backproject3d(q, d[:, 0].copy(), d[:, 1].copy(), d[:, 2].copy(), wts, r0, inv_dr, x, y, z,
                  out)
    Z, Y, X = np.meshgrid(z, y, x, indexing="ij")
    want = np.zeros_like(out)
    for v in range(5):
        u = (-(X * d[v, 0] + Y * d[v, 1] + Z * d[v, 2]) - r0) * inv_dr
        fk = np.floor(u)
        k = fk.astype(int)
        ok = (k >= 0) & (k < 15)
        kc = np.clip(k, 0, 14)
        want += wts[v] * np.where(ok, q[v, kc] + (u - fk) * (q[v, kc + 1] - q[v, kc]), 0.0)
    np.testing.assert_allclose(out, want, rtol=1e-12, atol=1e-12)


# --- the 2-D backprojection against references written here ---------------------------

#: The kernel's sampling, written out in numpy (per view, all pixels at once, the views
#: added in order) gives the same floating-point operations in the same order as the
#: kernel's documented arithmetic: the two agree bit for bit (tolerance 0), which is also
#: what the per-pixel loop the kernel replaced gave.
EXACT = 0.0
#: A textbook backprojection (r = −(x cos φ + y sin φ) rounded differently, np.interp)
#: agrees to this fraction of Σ_v w_v max|q_v|: u differs by a few ulps, so a sample moves
#: by a few ulps times the largest step between samples (2 max|q|) over ~60 bins.
TEXTBOOK_RTOL = 1e-12


def _plain_backprojection(q, c, s, w, r0, inv_dr, x, y, nearest, out0):
    """out0 plus Σ_v w_v q_v(u), u = (−y s_v − r0)·inv_dr + x·(−c_v·inv_dr), in numpy;
    pixels whose u is outside the samples are not touched at all."""
    out = out0.copy()
    n = q.shape[1]
    for v in range(w.size):
        u = ((-y * s[v] - r0) * inv_dr)[:, None] + x[None, :] * (-c[v] * inv_dr)
        if nearest:
            g = u + 0.5
            inside = (g >= 0) & (g < n)
            k = np.where(inside, g, 0.0).astype(np.int64)          # trunc = floor, g >= 0
            np.add(out, w[v] * q[v, k], out=out, where=inside)
            continue
        inside = (u >= 0) & (u < n - 1)
        uu = np.where(inside, u, 0.0)
        k = uu.astype(np.int64)
        kp = np.minimum(k + 1, n - 1)
        f = uu - k
        np.add(out, w[v] * (q[v, k] + f * (q[v, kp] - q[v, k])), out=out, where=inside)
        np.add(out, w[v] * q[v, n - 1], out=out, where=u == n - 1)
    return out


def _random_case(rng, nx, ny, n_views, n_bins, reach=1.5):
    """Random samples, weights and angles (non-uniform, unsorted), bins over [−1, 1]
    and pixel centres over ±reach (wider than the bins: pixels outside their reach)."""
    q = rng.normal(size=(n_views, n_bins))
    phi = rng.uniform(0.0, 2.0 * np.pi, n_views)
    w = rng.uniform(0.1, 1.0, n_views)
    x = np.linspace(-reach, reach, nx)
    y = np.linspace(-reach, reach, ny) + rng.uniform(-0.01, 0.01)
    return q, np.cos(phi), np.sin(phi), w, -1.0, (n_bins - 1) / 2.0, x, y


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_is_the_plain_loop_bit_for_bit(nearest):
    """Random data, non-uniform angles, odd and even view counts (views go in pairs), rows
    wider than one 1024-column chunk, a non-zero image to add to: exactly the plain
    backprojection."""
    rng = np.random.default_rng(7)
    for n_views, n_bins, nx, ny in [(37, 50, 2100, 3), (36, 2, 700, 5), (5, 1, 64, 4),
                                    (1, 257, 1025, 2)]:
        q, c, s, w, r0, inv_dr, x, y = _random_case(rng, nx, ny, n_views, n_bins)
        out0 = rng.normal(size=(ny, nx))
        out = out0.copy()
        backproject(q, c, s, w, r0, inv_dr, x, y, nearest, out)
        want = _plain_backprojection(q, c, s, w, r0, inv_dr, x, y, nearest, out0)
        assert np.max(np.abs(out - want)) <= EXACT
        assert np.array_equal(out, want)


def _expected_at(u, n, nearest):
    """The sample of q_k = k + 1 (k < n) at u: nearest rounds halves up and takes nothing
    from u = n − ½ on; linear is u + 1 on [0, n − 1], the last sample included."""
    if nearest:
        return np.floor(u + 0.5) + 1.0 if -0.5 <= u < n - 0.5 else 0.0
    return u + 1.0 if 0.0 <= u <= n - 1.0 else 0.0


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_samples_landing_exactly_on_samples_and_halves(nearest):
    """u on an integer and half-integer grid going up (cos φ = −1: u = x) and down
    (cos φ = 1: u = −x), and constant along rows (cos φ = ±0, sin φ = −1: u = y)."""
    n = 6
    q = np.arange(1.0, n + 1.0)[None, :]
    x = np.arange(-2.0, n + 1.5, 0.5)
    for cos, u in ((-1.0, x), (1.0, -x)):
        out = np.zeros((1, x.size))
        backproject(q, np.array([cos]), np.zeros(1), np.ones(1), 0.0, 1.0, x, np.zeros(1),
                    nearest, out)
        assert out[0].tolist() == [_expected_at(t, n, nearest) for t in u]
    y = np.array([-1.0, -0.5, 0.0, 2.5, n - 1.0, n - 0.5, n])
    for cos in (0.0, -0.0):
        out = np.zeros((y.size, 9))
        backproject(q, np.array([cos]), -np.ones(1), np.ones(1), 0.0, 1.0,
                    np.linspace(-1.0, 1.0, 9), y, nearest, out)
        assert out.tolist() == [[_expected_at(t, n, nearest)] * 9 for t in y]


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_agrees_with_a_textbook_backprojection(nearest):
    """Independent arithmetic (r = −(x cos φ + y sin φ), np.interp between bin centres,
    0 outside them) on random data, random non-uniform angles and weights and irregular,
    increasing pixel positions: within TEXTBOOK_RTOL."""
    rng = np.random.default_rng(11)
    n_views, n_bins = 45, 60
    q = rng.normal(size=(n_views, n_bins))
    phi = np.sort(rng.uniform(0.0, 2.0 * np.pi, n_views))
    w = rng.uniform(0.1, 1.0, n_views)
    x = np.sort(rng.uniform(-1.4, 1.4, 300))
    y = rng.uniform(-1.4, 1.4, 40)
    r0, dr = -1.0, 2.0 / (n_bins - 1)
    centres = r0 + dr * np.arange(n_bins)
    out = np.zeros((y.size, x.size))
    backproject(q, np.cos(phi), np.sin(phi), w, r0, 1.0 / dr, x, y, nearest, out)
    X, Y = np.meshgrid(x, y)
    want = np.zeros_like(out)
    for v in range(n_views):
        r = -(X * np.cos(phi[v]) + Y * np.sin(phi[v]))
        if nearest:
            k = np.floor((r - r0) / dr + 0.5)
            inside = (k >= 0) & (k < n_bins)
            want += w[v] * np.where(inside, q[v, np.clip(k, 0, n_bins - 1).astype(int)], 0.0)
        else:
            want += w[v] * np.interp(r, centres, q[v], left=0.0, right=0.0)
    scale = float(np.sum(w * np.max(np.abs(q), axis=1)))
    assert np.max(np.abs(out - want)) <= TEXTBOOK_RTOL * scale


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_adds_exactly_nothing_beyond_the_bins(nearest):
    """With samples over ranges [1, 3] only, pixels nearer the axis than 1 − a bin (|r| < 1
    − a bin in every view) keep their value bit for bit, and so does every pixel a lone
    view's samples do not reach; views whose u is not finite (y = ±inf, nan) add nothing
    either."""
    rng = np.random.default_rng(3)
    q, c, s, w, _, inv_dr, x, y = _random_case(rng, 301, 61, 24, 40, reach=3.0)
    r0 = 1.0
    out0 = rng.normal(size=(y.size, x.size))
    out = out0.copy()
    backproject(q, c, s, w, r0, inv_dr, x, y, nearest, out)
    near = np.hypot(*np.meshgrid(x, y)) < r0 - 1.0 / inv_dr
    assert near.sum() > 0.05 * near.size and np.array_equal(out[near], out0[near])
    assert not np.array_equal(out[~near], out0[~near])
    out = out0.copy()
    backproject(q[:1], c[:1], s[:1], w[:1], r0, inv_dr, x, y, nearest, out)
    u = ((-y * s[0] - r0) * inv_dr)[:, None] + x[None, :] * (-c[0] * inv_dr)
    top = q.shape[1] - 0.5 if nearest else q.shape[1] - 1.0
    beyond = (u < (-0.5 if nearest else 0.0)) | (u > top)
    assert beyond.any() and np.array_equal(out[beyond], out0[beyond])
    odd = np.array([np.inf, -np.inf, np.nan])
    out = out0[:3].copy()
    backproject(q, c, s, w, r0, inv_dr, x, odd, nearest, out)
    assert np.array_equal(out, out0[:3])


@pytest.mark.parametrize("nearest", [False, True])
def test_backproject_with_unordered_pixel_positions(nearest):
    """x out of order (or with nan) takes the per-pixel loop: still the plain
    backprojection, bit for bit."""
    rng = np.random.default_rng(5)
    q, c, s, w, r0, inv_dr, x, y = _random_case(rng, 120, 4, 9, 30)
    x = rng.permutation(x)
    x[7] = np.nan
    out0 = rng.normal(size=(y.size, x.size))
    out = out0.copy()
    backproject(q, c, s, w, r0, inv_dr, x, y, nearest, out)
    want = _plain_backprojection(q, c, s, w, r0, inv_dr, x, y, nearest, out0)
    assert np.array_equal(out, want)
