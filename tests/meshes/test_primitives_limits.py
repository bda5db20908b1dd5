"""The tessellations refuse what they cannot build: an icosphere past the allocation cap
(its faces grow as 20·4^subdivisions) before trimesh builds anything, and a prism of a
height that is not finite and positive."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.materials import DARK_GRAY
from meshladar.meshes import primitives

trimesh = pytest.importorskip("trimesh")


@pytest.fixture
def no_build(monkeypatch):
    """Building an icosphere fails the test: a refusal must come first."""
    def build(*args, **kwargs):
        raise AssertionError("the icosphere was built before the size was checked")

    monkeypatch.setattr(trimesh.creation, "icosphere", build)


@pytest.mark.parametrize("call", [
    lambda n: primitives.icosphere(n),
    lambda n: primitives.sphere((0.0, 0.0, 0.0), 1.0, 0, subdivisions=n),
    lambda n: primitives.ellipsoid((0.0, 0.0, 0.0), (1.0, 2.0, 3.0), 0, subdivisions=n),
], ids=["icosphere", "sphere", "ellipsoid"])
@pytest.mark.parametrize("n", [10, 30, 2 ** 53])
def test_an_icosphere_past_the_allocation_cap_is_refused_unbuilt(no_build, call, n):
    with pytest.raises(ParameterError, match=rf"^subdivisions: an icosphere of {n} "
                                             r"subdivisions .* GiB meshladar allocates at "
                                             r"once; use fewer subdivisions \(at most 9\)"):
        call(n)


def test_the_largest_allowed_icosphere_is_within_the_cap():
    need = 20 * 4 ** 9 * primitives.ICOSPHERE_FACE_BYTES
    assert need <= 4 * 2 ** 30 < 4 * need
    v, f = primitives.icosphere(2)
    assert f.shape == (320, 3) and np.allclose(np.linalg.norm(v, axis=1), 1.0)


@pytest.mark.parametrize("height, message", [
    (-1.0, r"^height must be in \(0, inf\); got -1.0"),
    (0.0, r"^height must be in \(0, inf\); got 0.0"),
    (math.nan, r"^height must be finite and in \(0, inf\); got nan"),
    (math.inf, r"^height must be finite and in \(0, inf\); got inf"),
])
def test_a_prism_needs_a_finite_positive_height(height, message):
    with pytest.raises(ParameterError, match=message):
        primitives.prism(ml.Disk((0.0, 0.0), 0.5, DARK_GRAY), 8, height, 0)


def test_a_prism_needs_a_finite_z0():
    with pytest.raises(ParameterError, match=r"^z0 must be finite"):
        primitives.prism(ml.Disk((0.0, 0.0), 0.5, DARK_GRAY), 8, 1.0, 0, z0=math.nan)
    part = primitives.prism(ml.Disk((0.0, 0.0), 0.5, DARK_GRAY), 8, 2.0, 0, z0=1.0)
    assert np.ptp(part.vertices[:, 2]) == 2.0 and part.vertices[:, 2].min() == 0.0
