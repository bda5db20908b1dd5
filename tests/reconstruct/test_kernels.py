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
