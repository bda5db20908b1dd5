"""convex_hull leaves the caller's points as they were: its read-only answer is a new
array, never the caller's own array made read-only in place."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.meshes import convex_hull


@pytest.mark.parametrize("points", [
    np.random.default_rng(0).normal(size=(10, 3)),                 # 64 or fewer: all kept
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]] * 20),
    np.random.default_rng(1).normal(size=(200, 3)),                 # Qhull drops some
], ids=["few", "flat-sheet", "many"])
def test_the_hull_leaves_the_callers_array_writeable_and_unchanged(points):
    before = points.copy()
    hull = convex_hull(points)
    assert points.flags.writeable                     # the caller's flags are untouched
    assert not np.shares_memory(hull, points)
    assert not hull.flags.writeable and hull.flags.c_contiguous
    np.testing.assert_array_equal(points, before)
    points[0, 0] += 1.0                               # still the caller's to change
    assert hull.dtype == points.dtype
    assert {tuple(p) for p in hull} <= {tuple(p) for p in before}     # the same points
    if len(before) <= 64 or np.ptp(before[:, 2]) == 0:                 # nothing dropped
        np.testing.assert_array_equal(hull, before)
