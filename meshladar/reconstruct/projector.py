"""The operator protocol of reconstruction's projectors.

A :class:`Projector` is a :class:`scipy.sparse.linalg.LinearOperator` from an image on a
:class:`~meshladar.forward.siddon.PixelGrid` to a sinogram's (n_views, n_bins) bin
integrals, with its exact adjoint as ``A.T``. ``A @ image`` takes and gives arrays in their
own shapes (image (ny, nx) → (n_views, n_bins); ``A.T @ values`` back); flat vectors go
through scipy's ``matvec`` and ``rmatvec``, so a projector also composes with scipy's
solvers (``lsqr``, ``cg``). The projectors themselves (Siddon lines, the pixel-driven pair,
the surface segments) are in :mod:`meshladar.reconstruct.operators`, which re-exports
:class:`Projector`.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.linalg import LinearOperator

from .._validate import finite_array

__all__ = ["Projector"]


class Projector(LinearOperator):
    """A: image on ``grid`` → (n_views, n_bins) bin integrals; ``A.T`` its exact adjoint.

    Subclasses implement ``_forward(image) -> (n_views, n_bins)`` and ``_backward(values)
    -> image``; this class makes them a scipy ``LinearOperator`` (flat vectors) that also
    maps arrays in their own shapes.

    The operator's ``shape`` is (n_views · n_bins, ny · nx), its dtype float64; flat
    vectors are images raveled in row-major (ny, nx) order and data raveled in
    (n_views, n_bins) order.

    Parameters
    ----------
    grid : meshladar.forward.siddon.PixelGrid
        The image's pixel grid (ny × nx pixels).
    angles_deg : (n_views,) array_like
        View angles about z, degrees (w = (cos φ, sin φ)); flattened.
    bin_edges : (n_bins + 1,) array_like
        Range bin edges, scene units (range r = −p·w); flattened.

    Attributes
    ----------
    grid : meshladar.forward.siddon.PixelGrid
        As given.
    angles_deg, bin_edges : ndarray of float64
        As given, checked finite and flattened.
    n_views, n_bins : int
        The data's shape, :attr:`data_shape`.

    Raises
    ------
    ParameterError
        When ``angles_deg`` or ``bin_edges`` holds a value that is not finite.
    """

    def __init__(self, grid, angles_deg, bin_edges):
        self.grid = grid
        self.angles_deg = finite_array("angles_deg", angles_deg).ravel()
        self.bin_edges = finite_array("bin_edges", bin_edges).ravel()
        self.n_views, self.n_bins = self.angles_deg.size, self.bin_edges.size - 1
        super().__init__(np.float64, (self.n_views * self.n_bins, grid.nx * grid.ny))

    @property
    def data_shape(self):
        """(n_views, n_bins): the shape of ``A @ image``."""
        return (self.n_views, self.n_bins)

    def _forward(self, image):
        raise NotImplementedError

    def _backward(self, values):
        raise NotImplementedError

    def _matvec(self, x):
        return self._forward(np.reshape(x, self.grid.shape)).ravel()

    def _rmatvec(self, y):
        return self._backward(np.reshape(y, self.data_shape)).ravel()

    def _adjoint(self):
        return _Adjoint(self)

    _transpose = _adjoint

    def dot(self, x):
        """A x: an image in its own shape to (n_views, n_bins), anything else as scipy.

        Parameters
        ----------
        x : array_like, LinearOperator or scalar
            A (ny, nx) image on ``grid``; or what ``scipy.sparse.linalg.LinearOperator.dot``
            takes: a flat (ny · nx,) image, a (ny · nx, k) matrix of k flat images, an
            operator to compose with or a scalar to scale by.

        Returns
        -------
        ndarray or LinearOperator
            (n_views, n_bins) bin integrals for an image in its own shape; otherwise
            scipy's answer: a (n_views · n_bins,) vector, a (n_views · n_bins, k) array, or
            the composed or scaled operator.

        Raises
        ------
        ValueError
            From scipy, when ``x`` is an array of neither shape.
        """
        if not isinstance(x, LinearOperator) and np.shape(x) == self.grid.shape:
            return self._forward(x)
        return super().dot(x)

    def __matmul__(self, x):
        return self.dot(x)


class _Adjoint(LinearOperator):
    """Aᵀ of a :class:`Projector`: (n_views, n_bins) values → image."""

    def __init__(self, forward):
        self._f = forward
        super().__init__(np.float64, forward.shape[::-1])

    def _matvec(self, y):
        return self._f._rmatvec(y)

    def _rmatvec(self, x):
        return self._f._matvec(x)

    def _adjoint(self):
        return self._f

    _transpose = _adjoint

    def dot(self, y):
        if not isinstance(y, LinearOperator) and np.shape(y) == self._f.data_shape:
            return self._f._backward(y)
        return super().dot(y)

    def __matmul__(self, y):
        return self.dot(y)
