"""Connected components of a mesh's vertex graph (meshladar.meshes.checks.components, which
the mesh report's closed-body test uses) against scipy.sparse.csgraph, the reference."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from meshladar.meshes.checks import components


def _scipy_labels(n, a, b):
    graph = coo_matrix((np.ones(a.size, np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


@pytest.mark.parametrize("n, m", [(1, 0), (10, 5), (1000, 800), (100_000, 60_000),
                                  (100_000, 100_000), (50_000, 200_000)])
def test_components_partition_as_scipy_on_random_graphs(n, m):
    """The same partition as scipy's, its components in the same order (by their smallest
    vertex), each labelled by its smallest vertex, on seeded random graphs from mostly
    isolated vertices to one giant component."""
    rng = np.random.default_rng(n + m)
    a, b = rng.integers(0, n, m), rng.integers(0, n, m)
    label = components(n, a, b)
    roots, body = np.unique(label, return_inverse=True)
    np.testing.assert_array_equal(body.ravel(), _scipy_labels(n, a, b))
    np.testing.assert_array_equal(label[roots], roots)          # a root labels itself
    assert np.all(label <= np.arange(n))                        # the smallest vertex


def test_a_long_path_in_random_order_is_one_component():
    """200,000 vertices joined in a chain visited in random order (the slowest case for
    min-label hooking), and two such chains: one label each."""
    rng = np.random.default_rng(7)
    order = rng.permutation(200_000)
    assert np.all(components(200_000, order[:-1], order[1:]) == 0)
    a = np.concatenate([order[:99_999], order[100_000:-1]])
    b = np.concatenate([order[1:100_000], order[100_001:]])
    label = components(200_000, a, b)
    assert np.unique(label).size == 2
    np.testing.assert_array_equal(np.unique(label, return_inverse=True)[1].ravel(),
                                  _scipy_labels(200_000, a, b))
