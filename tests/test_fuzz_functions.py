"""Property-based fuzz over the newer surfaces' functions (issue 29): each keyword argument
of receive, Waveforms.realise / detection_probability / scaled, resolve, Returns.realise,
the iterative solvers, fbp, fbp3d, fit_coatings, design_views, find_shapes and compensate
given arbitrary values (0, ±inf, NaN, 1e±308, subnormals, huge integers, None, booleans,
text). The only outcomes allowed are a result whose arrays are finite, or a MeshladarError
of one line. (test_fuzz_surfaces.py does the constructors.)"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meshladar as ml
from meshladar.errors import LobeSamplingWarning, MeshladarError
from meshladar.fit import design_views, find_shapes, fit_coatings
from meshladar.forward.resolved import resolve
from meshladar.noise import Noise
from meshladar.reconstruct.compensation import compensate
from meshladar.reconstruct.iterative import cgls, sart, sirt, tv_fista
from meshladar.waveforms import GaussianPulse, receive

#: Examples per (function, argument); the fits' examples cost ~0.1 s each.
FUZZ = settings(max_examples=25, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow,
                                       HealthCheck.function_scoped_fixture])
#: floats at the extremes, integers beyond float64, and values of the wrong kind
extreme = st.one_of(st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True),
                    st.sampled_from([0.0, -0.0, -1.0, 1e-308, 5e-324, 1e308, -1e308, 1e-200,
                                     float("nan"), float("inf")]),
                    st.integers(-(10 ** 400), 10 ** 400), st.none(), st.booleans(),
                    st.text(max_size=3))
#: counts (iterations, sizes, samples): the same, but a valid count stays small, so an
#: accepted one runs in milliseconds (a huge one must be refused for its memory)
count = st.one_of(extreme.filter(lambda v: not isinstance(v, int) or isinstance(v, bool)
                                 or v < 0 or v > 10 ** 12),
                  st.integers(-2, 12))


@pytest.fixture(scope="module")
def data():
    disk = ml.Disk((0.1, 0.0), 0.5, ml.brdf.SandfordRobertson(0.1, 0.4, 0.2, 0.02),
                   name="disk")
    scene = ml.Scene([disk])
    ladar = ml.Ladar(np.arange(0.0, 360.0, 20.0), ml.Ladar.centered(24, 1.6 / 24).bin_edges)
    sino = ml.simulate(scene, ladar, model="analytic")
    waves = receive(sino, sample_rate=2e9, pulse=GaussianPulse(2e-9)).scaled(1e4)
    with warnings.catch_warnings():        # data to fuzz with: the glint need not be
        warnings.simplefilter("ignore", LobeSamplingWarning)          # resolved (1.6 rays)
        returns = resolve(scene, ladar, _axes(0.5)).scaled(1e3)
    return dict(scene=scene, ladar=ladar, sino=sino, waves=waves, returns=returns)


def _axes(top):
    """Range bins and two elevation bins up to ``top`` (a resolved image per view)."""
    return [("range", np.linspace(-0.8, 0.8, 25)), ("elevation", [-0.5, 0.0, top])]


def _outcome(call):
    """The call's result, or None when it refused with one clear line."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")          # numpy's own warnings are defects
            warnings.simplefilter("ignore", ml.errors.MeshladarWarning)     # (first match)
            return call()
    except MeshladarError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 1000, str(exc)
        return None


def _arrays(result):
    """Every float array a result carries (its values, image, estimate, σ)."""
    if isinstance(result, np.ndarray):
        yield result
    elif isinstance(result, dict):
        for v in result.values():
            yield from _arrays(v)
    elif isinstance(result, (list, tuple)):
        for v in result:
            yield from _arrays(v)
    else:
        for name in ("values", "image", "estimate", "views"):
            v = getattr(result, name, None)
            if isinstance(v, np.ndarray):
                yield v


def _check(result):
    if result is None:
        return
    stderr = getattr(result, "stderr", None)     # inf marks an undetermined parameter
    assert stderr is None or not np.any(np.isnan(stderr)), stderr
    for a in _arrays(result):
        if a.dtype.kind == "f":
            assert np.all(np.isfinite(a)), (type(result).__name__, a)


def _iterative(solver, **fuzzed):
    """A call of ``solver`` at 8² for 3 iterations, with each fuzzed argument's value
    made from the drawn one."""
    return lambda d, v: solver(d["sino"], **{"size": 8, "n_iter": 3,
                                             **{k: f(v) for k, f in fuzzed.items()}})


CALLS = {
    "receive.sample_rate": lambda d, v: receive(d["sino"], sample_rate=v),
    "receive.standoff": lambda d, v: receive(d["sino"], sample_rate=1e9, standoff=v),
    "receive.oversample": lambda d, v: receive(d["sino"], sample_rate=1e9, oversample=v),
    "receive.response": lambda d, v: receive(d["sino"], sample_rate=1e9, response=v),
    "Waveforms.scaled": lambda d, v: d["waves"].scaled(v),
    "resolve.edges": lambda d, v: resolve(d["scene"], d["ladar"], _axes(v)),
    "resolve.ray_spacing": lambda d, v: resolve(d["scene"], d["ladar"], _axes(0.5),
                                                ray_spacing=v),
    "Returns.realise.dwell": lambda d, v: d["returns"].realise(
        Noise(background_rate=1e6), 1, seed=0, dwell=v),
    "Returns.realise.noise": lambda d, v: d["returns"].realise(Noise(gain=v), 1, seed=0),
    "Waveforms.realise.n": lambda d, v: d["waves"].realise(Noise(), v),
    "Waveforms.realise.seed": lambda d, v: d["waves"].realise(Noise(), 1, seed=v),
    "Waveforms.detection.threshold": lambda d, v: d["waves"].detection_probability(
        Noise(), v, n=10, seed=0),
    "Waveforms.detection.n": lambda d, v: d["waves"].detection_probability(
        Noise(), 1.0, n=v, seed=0),
    "sirt.size": _iterative(sirt, size=lambda v: v),
    "sirt.extent": _iterative(sirt, extent=lambda v: v),
    "sirt.n_iter": _iterative(sirt, n_iter=lambda v: v),
    "sirt.tol": _iterative(sirt, tol=lambda v: v),
    "sirt.center": _iterative(sirt, center=lambda v: (v, 0.0)),
    "sirt.rays_per_bin": _iterative(sirt, rays_per_bin=lambda v: v),
    "sart.relax": _iterative(sart, relax=lambda v: v),
    "sart.subsets": _iterative(sart, subsets=lambda v: v),
    "cgls.extent": _iterative(cgls, extent=lambda v: v),
    "tv_fista.tv": _iterative(tv_fista, tv=lambda v: v),
    "tv_fista.weights": _iterative(tv_fista, weights=lambda v: np.full((18, 24), v)),
    "fbp.size": lambda d, v: ml.fbp(d["sino"], size=v),
    "fbp.extent": lambda d, v: ml.fbp(d["sino"], size=8, extent=v),
    "fbp.center": lambda d, v: ml.fbp(d["sino"], size=8, center=(0.0, v)),
    "fit_coatings.photons_per_unit": lambda d, v: fit_coatings(
        d["scene"], d["sino"], noise="poisson", photons_per_unit=v, samples=256),
    "fit_coatings.speckle_cells": lambda d, v: fit_coatings(
        d["scene"], d["sino"], noise="poisson",
        photons_per_unit=1e4, speckle_cells=v, samples=256),
    "fit_coatings.background": lambda d, v: fit_coatings(d["scene"], d["sino"], background=v,
                                                         samples=256),
    "fit_coatings.bounds": lambda d, v: fit_coatings(d["scene"], d["sino"],
                                                     bounds={"disk.b": (v, 1.0)}, samples=256),
    "fit_coatings.initial": lambda d, v: fit_coatings(d["scene"], d["sino"],
                                                      initial={"disk.e": v}, samples=256),
    "fit_coatings.samples": lambda d, v: fit_coatings(d["scene"], d["sino"], samples=v),
    "fit_coatings.kernel_tol": lambda d, v: fit_coatings(d["scene"], d["sino"], samples=256,
                                                         kernel_tol=v),
    "fit_coatings.max_iter": lambda d, v: fit_coatings(d["scene"], d["sino"], samples=256,
                                                       max_iter=v),
    "fit_coatings.seed": lambda d, v: fit_coatings(d["scene"], d["sino"], samples=256,
                                                   bootstrap=2, seed=v),
    "design_views.budget": lambda d, v: design_views(d["scene"], v, ladar=d["ladar"],
                                                     samples=256),
    "design_views.photons_per_unit": lambda d, v: design_views(
        d["scene"], 4, ladar=d["ladar"], photons_per_unit=v, samples=256),
    "find_shapes.size": lambda d, v: find_shapes(d["sino"], size=v),
    "find_shapes.extent": lambda d, v: find_shapes(d["sino"], size=64, extent=v),
    "find_shapes.tol_bins": lambda d, v: find_shapes(d["sino"], size=64, tol_bins=v),
    "find_shapes.min_share": lambda d, v: find_shapes(d["sino"], size=64, min_share=v),
    "find_shapes.max_shapes": lambda d, v: find_shapes(d["sino"], size=64, max_shapes=v),
    "find_shapes.seed": lambda d, v: find_shapes(d["sino"], size=64, seed=v),
    "compensate.threshold": lambda d, v: compensate(d["sino"], d["scene"].shapes[0].material,
                                                    size=8, n_iter=2, threshold=v),
    "compensate.sigma": lambda d, v: compensate(d["sino"], d["scene"].shapes[0].material,
                                                size=8, n_iter=2, sigma=v),
    "compensate.smooth": lambda d, v: compensate(d["sino"], d["scene"].shapes[0].material,
                                                 size=8, n_iter=2, smooth=v),
    "compensate.blur_deg": lambda d, v: compensate(d["sino"], d["scene"].shapes[0].material,
                                                   size=8, n_iter=2, blur_deg=v),
}
#: the arguments that are counts: fuzzed with small valid values and invalid ones
COUNTS = {"receive.oversample", "Waveforms.realise.n", "Waveforms.detection.n", "sirt.size",
          "sirt.n_iter", "sirt.rays_per_bin", "sart.subsets", "fbp.size",
          "fit_coatings.samples", "fit_coatings.max_iter", "design_views.budget",
          "find_shapes.size", "find_shapes.max_shapes"}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CALLS))
def test_functions_refuse_or_return_finite_numbers(name, data):
    @FUZZ
    @given(value=count if name in COUNTS else extreme)
    def run(value):
        _check(_outcome(lambda: CALLS[name](data, value)))

    run()
