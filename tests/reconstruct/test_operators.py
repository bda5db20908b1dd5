"""The projectors as one operator protocol (meshladar.reconstruct.operators): every
projector is a scipy LinearOperator whose ``.T`` is its exact adjoint, in the arrays' own
shapes and as flat vectors."""

from __future__ import annotations

import importlib
import pkgutil

import numpy as np
import pytest
from scipy.sparse.linalg import LinearOperator

import meshladar.reconstruct
from meshladar.brdf import Lambertian
from meshladar.reconstruct.operators import (LinearProjector, Projector, RangeProjector,
                                             SurfaceProjector)
from meshladar.reconstruct.surface import Surface, surface_weights
from meshladar.forward.siddon import PixelGrid

SIZE = 48
ANGLES = np.arange(0.0, 360.0, 12.0)                 # 30 views, opposite pairs included
EDGES = np.linspace(-1.0, 1.0, 41)                   # 40 bins symmetric about 0
#: Both sides of ⟨A x, y⟩ = ⟨x, Aᵀ y⟩ add the same products x_i A_ij y_j (A ≥ 0, x, y > 0,
#: so no cancellation) in different orders: they differ by rounding only, at most about
#: n·eps relative for n terms in the worst case and ~√n·eps in practice (n ≲ 1e5 here:
#: bound 2e-11, measured at most 2.6e-16). 1e-12 is thousands of times the measured
#: rounding and still catches any wrong weight, a dropped bin or a missed view.
ADJOINT_RTOL = 1e-12


def _ring_surface(radius=0.6):
    """A surface of one point per pixel on a circle (pixel centres moved onto it, radial
    normals): each pixel once, as estimate_surface gives them."""
    pix = 2.0 / SIZE
    c = -1.0 + (np.arange(SIZE) + 0.5) * pix
    X, Y = np.meshgrid(c, c)
    rows, cols = np.nonzero(np.abs(np.hypot(X, Y) - radius) < 0.5 * pix)
    p = np.stack([X[rows, cols], Y[rows, cols]], axis=1)
    normals = p / np.linalg.norm(p, axis=1, keepdims=True)
    return Surface(radius * normals, rows, cols, normals, SIZE, 1.0, (0.0, 0.0))


def _surface_projector(smooth):
    surf = _ring_surface()
    return SurfaceProjector(surf, ANGLES, EDGES, surface_weights(surf, ANGLES, Lambertian(1.0)),
                            smooth)


PROJECTORS = {
    "siddon": lambda: RangeProjector(PixelGrid.square(SIZE, 1.0), ANGLES, EDGES,
                                     rays_per_bin=3),
    "siddon-offset": lambda: RangeProjector(PixelGrid.square(SIZE, 1.0, (0.2, -0.1)),
                                            ANGLES + 0.5, np.linspace(-1.2, 0.9, 33)),
    "splat-folded": lambda: LinearProjector(PixelGrid.square(SIZE, 1.0), ANGLES, EDGES),
    "splat-unfolded": lambda: LinearProjector(PixelGrid.square(SIZE, 1.0), ANGLES,
                                              EDGES + 1e-3),
    "surface": lambda: _surface_projector(0.0),
    "surface-smoothed": lambda: _surface_projector(2.0),
}


@pytest.mark.parametrize("name", sorted(PROJECTORS))
def test_adjoint_is_exact(name):
    """⟨A x, y⟩ = ⟨x, Aᵀ y⟩ for every projector, and the protocol: a LinearOperator of
    shape (n_views·n_bins, n_pixels) whose flat matvec/rmatvec agree with ``@`` on arrays
    in their own shapes, and whose transpose's transpose is itself."""
    A = PROJECTORS[name]()
    assert isinstance(A, Projector) and isinstance(A, LinearOperator)
    assert A.shape == (A.n_views * A.n_bins, SIZE * SIZE)
    rng = np.random.default_rng(0)
    x, y = rng.random(A.grid.shape), rng.random(A.data_shape)
    Ax, ATy = A @ x, A.T @ y
    assert Ax.shape == A.data_shape and ATy.shape == A.grid.shape
    lhs, rhs = float(np.sum(Ax * y)), float(np.sum(x * ATy))
    assert abs(lhs - rhs) <= ADJOINT_RTOL * abs(lhs)
    np.testing.assert_array_equal(A.matvec(x.ravel()), Ax.ravel())
    np.testing.assert_array_equal(A.rmatvec(y.ravel()), ATy.ravel())
    np.testing.assert_array_equal(A.T.matvec(y.ravel()), ATy.ravel())
    assert A.T.T is A and A.H.H is A


def test_reconstruct_package_face():
    """The package face re-exports FBP's names, no public name shadows one of its modules
    (``import meshladar.reconstruct.<module> as m`` gives the module), and importing it
    leaves numba for the first compiled call."""
    for name in ("fbp", "Image", "log_radiance", "clip_radiance", "FILTERS",
                 "fourier_filter", "resample_uniform", "noise_floor"):
        assert name in meshladar.reconstruct.__all__
    pkg = meshladar.reconstruct
    for mod in pkgutil.iter_modules(pkg.__path__):
        module = importlib.import_module(f"{pkg.__name__}.{mod.name}")
        assert getattr(pkg, mod.name, module) is module, f"{mod.name} is shadowed"
