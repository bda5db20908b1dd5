"""design_views takes a trace's Hits as its docstring says: their kernel is built from their
own rays, so design_views' default samples (meant for a Scene) is not passed on, and a
samples given with Hits is refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.fit import coating_kernel, design, design_views
from meshladar.materials import ALUMINUM

SCENE = ml.Scene([ml.Disk((0.1, 0.0), 0.5, ALUMINUM, name="disk")]).tessellate(64)
LAD = ml.Ladar(np.arange(0.0, 360.0, 30.0), ml.Ladar.centered(16, 1.6 / 16).bin_edges)


@pytest.fixture(scope="module")
def hits():
    return ml.trace(SCENE, LAD, rays_per_bin=4)


def test_design_views_of_hits_is_the_design_of_their_kernel(hits):
    """With the default samples (4096) design_views(hits) failed: coating_kernel refuses
    samples with Hits."""
    got = design_views(hits, 3)
    want = design_views(coating_kernel(hits), 3)
    np.testing.assert_array_equal(got.chosen, want.chosen)
    np.testing.assert_array_equal(got.information, want.information)
    assert got.names == want.names == ("aluminum.rho_d", "aluminum.epsilon", "aluminum.b",
                                       "aluminum.e")
    np.testing.assert_array_equal(design_views(hits, 3, samples=None).chosen, got.chosen)


@pytest.mark.parametrize("samples", [100, 8192.0, "4096"])
def test_samples_other_than_the_default_are_refused_with_hits(hits, samples):
    with pytest.raises(ParameterError, match=r"^samples applies to a Scene; Hits carry their "
                                             r"own rays.*got " + repr(samples)):
        design_views(hits, 3, samples=samples)


def test_a_budget_that_is_not_a_count_is_refused_before_any_tracing(monkeypatch):
    """A budget of 0, 2.5 or "3" is refused before the geometry is traced."""
    def no_kernel(*args, **kwargs):
        raise AssertionError("a kernel was built before the budget was checked")

    monkeypatch.setattr(design, "_kernel_of", no_kernel)
    scene = ml.phantoms.scene("disk_pair", large=ml.materials.DARK_GRAY,
                              small=ml.materials.ALUMINUM)
    for budget in (0, 2.5, "3"):
        with pytest.raises(ParameterError, match="budget"):
            design.design_views(scene, budget, ladar=ml.Ladar.paper(angles_deg=[0.0, 90.0]))
