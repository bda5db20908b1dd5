"""Property-based tests: random valid and invalid inputs never give NaN/inf or an
unexplained exception; each failure names its argument."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meshladar as ml
from meshladar.errors import GeometryError, LobeSamplingWarning, MeshladarError, ParameterError

FAST = settings(max_examples=60, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
unit = st.floats(0.0, 1.0, allow_nan=False)
anything = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-5, 5),
                     st.text(max_size=3), st.none(), st.booleans())


@FAST
@given(rho_d=unit, epsilon=unit, b=unit, e=st.floats(1e-12, 1.0),
       lobes=st.sampled_from(["both", "diffuse", "specular"]),
       theta=st.lists(st.floats(-10, 10, allow_nan=False), min_size=1, max_size=20))
def test_valid_coatings_give_finite_nonnegative_brdf(rho_d, epsilon, b, e, lobes, theta):
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ml.errors.EnergyConservationWarning)
            m = ml.SandfordRobertson(rho_d, epsilon, b, e, lobes=lobes)
    except ParameterError as exc:
        # the only refusal of in-range parameters is the energy bound, and it says so
        assert "not energy-conserving" in str(exc) and lobes != "diffuse"
        assert rho_d + epsilon > ml.brdf.diffuse_normalization(b)
        return
    t = np.array(theta)
    for projected in (False, True):
        f = m.monostatic(t, projected=projected)
        assert np.all(np.isfinite(f)) and np.all(f >= 0)
    if m.has_specular:                                   # energy: ρs ≥ 0 everywhere
        assert np.all(m.specular_reflectance(t) >= 0)


@pytest.mark.slow
@FAST
@given(name=st.sampled_from(["rho_d", "epsilon", "b", "e", "lobes"]), value=anything)
def test_invalid_coatings_name_the_argument(name, value):
    params = dict(rho_d=0.03, epsilon=0.5, b=0.1, e=0.17)
    params[name] = value
    try:
        ml.SandfordRobertson(**params)
    except ValueError as exc:
        assert isinstance(exc, MeshladarError) and name in str(exc)


coord = st.one_of(st.floats(-1, 1, width=32), st.sampled_from([math.nan, math.inf]))


@FAST
@given(vertices=st.lists(st.tuples(coord, coord, coord), min_size=3, max_size=8),
       faces=st.lists(st.tuples(*[st.integers(0, 7)] * 3), min_size=1, max_size=8),
       flip=st.booleans(), angle=st.floats(0, 360))
def test_random_small_meshes(vertices, faces, flip, angle):
    v = np.array(vertices, dtype=np.float64)
    f = np.array(faces)[:, ::-1] if flip else np.array(faces)
    try:
        part = ml.meshes.MeshPart(v, f, 0)
        scene = ml.Scene.from_parts([part], [ml.materials.DARK_GRAY])
    except GeometryError as exc:
        assert any(w in str(exc) for w in ("vertices must be finite", "faces index vertices",
                                          "no faces"))
        return
    lad = ml.Ladar([angle, angle + 90.0], np.linspace(-2, 2, 17))
    sino = ml.simulate(scene, lad, model="mesh", mode="3d", ray_spacing=0.05)
    assert np.all(np.isfinite(sino.values)) and np.all(sino.values >= 0)
    assert len(sino.info["back_face_hits"]) == 2


@FAST
@given(edges=st.lists(st.floats(-2, 2, allow_nan=False), min_size=2, max_size=12),
       angles=st.lists(st.floats(-720, 720, allow_nan=False), min_size=1, max_size=5),
       spacing=st.floats(0.005, 0.5))
def test_random_ladar_setups(edges, angles, spacing):
    scene = ml.Scene([ml.Disk((0.1, 0.0), 0.5, ml.materials.ALUMINUM)])
    e = np.array(edges)
    try:
        lad = ml.Ladar(angles, e)
    except ParameterError as exc:
        assert "bin_edges must be strictly increasing" in str(exc)
        assert np.any(np.diff(e) <= 0)
        return
    for kw in ({}, {"model": "mesh", "ray_spacing": spacing}):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sino = ml.simulate(scene, lad, **kw)
        assert np.all(np.isfinite(sino.values)) and np.all(sino.values >= 0)
        # a run that returns nothing says so, and only then; the mesh model's rays, 0.005
        # apart or more, cannot find aluminium's glint (two rays across its lobe need
        # 0.0023 on the disk's 1024 facets) and say that, always
        empty = [w for w in caught if "all zeros" in str(w.message)]
        assert len(empty) == (0 if sino.values.any() else 1)
        lobes = [w for w in caught if issubclass(w.category, LobeSamplingWarning)]
        assert len(lobes) == (1 if kw else 0)
        assert len(caught) == len(empty) + len(lobes)
    # the analytic total never exceeds the unbinned total (bins may cut part of it off)
    full = ml.simulate(scene, ml.Ladar(angles, [-3.0, 3.0])).total()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ml.errors.MeshladarWarning)
        assert np.all(ml.simulate(scene, lad).total() <= full * (1 + 1e-12))


@FAST
@given(theta=st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                       st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1,
                                max_size=4)))
def test_monostatic_rejects_nonfinite_theta_by_name(theta):
    arr = np.asarray(theta, dtype=float)
    if np.all(np.isfinite(arr)):
        assert np.all(np.isfinite(ml.materials.DARK_GRAY.monostatic(theta)))
    else:
        with pytest.raises(ParameterError, match="theta must be finite"):
            ml.materials.DARK_GRAY.monostatic(theta)
