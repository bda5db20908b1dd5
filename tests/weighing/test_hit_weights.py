"""The weight per unit of a coating's projected-weight table (per_table_weight, what a
coating kernel multiplies its θ table by) times that table is weigh's own per-hit weight,
up to and including exactly grazing hits (cos θ = 0, which a direction vector in the
surface gives)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import projected_weight
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.weighing import per_table_weight, scaled, weights

SCENE = ml.Scene([ml.Disk((0.0, 0.0), 0.5, ALUMINUM, name="disk")]).tessellate(32)
LAD = ml.Ladar(np.array([0.0, 90.0]), ml.Ladar.centered(16, 1.2 / 16).bin_edges)


@pytest.fixture(scope="module")
def grazing_hits():
    """A trace's hits with the first two made exactly grazing (cos θ = 0, sin θ = 1)."""
    hits = ml.trace(SCENE, LAD, rays_per_bin=2)
    cos, sin = np.array(hits.cos_theta), np.array(hits.sin_theta)
    cos[:2], sin[:2] = 0.0, 1.0
    return dataclasses.replace(hits, cos_theta=cos, sin_theta=sin)


@pytest.mark.parametrize("coating", [ALUMINUM, DARK_GRAY], ids=["aluminum", "dark gray"])
@pytest.mark.parametrize("power", [False, True], ids=["paper", "power"])
def test_the_tabulated_weight_is_weighs_weight_at_grazing(grazing_hits, coating, power):
    """Under "paper" cos θ was floored at 1e-300 where the BRDF floors it at cos(fl(π/2))
    = 6.1e-17: an exactly grazing hit weighed ~1e283 times weigh's (1e295 for aluminium)."""
    h = grazing_hits
    c, s = np.asarray(h.cos_theta), np.asarray(h.sin_theta)
    got = per_table_weight(h, power) * projected_weight(coating, c, s)
    want = scaled(weights(c, s, h.material, (coating,), float(h.area), power=power),
                  h.weight_factor, h.receive_factor, power=power)
    assert np.all(np.isfinite(got)) and np.max(got[:2]) < 1e15
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
