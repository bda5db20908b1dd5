"""A mesh scene's coating kernel traced from its Scene (meshladar.fit): it is the mesh model's
sum, it is traced again at finer spacings when a fit asks, and a fit on it reports the
kernel's error and carries it in its σ. Data from the mesh model's own compiled loop
(simulate), never from the kernel; the coverage test's at a finer ray spacing than the
kernel's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import SandfordRobertson
from meshladar.errors import ParameterError
from meshladar.fit import coating_kernel, fit_coatings
from meshladar.fit._resolution import MESH_ERROR_FACTOR
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk

LAD = Ladar(np.arange(0.0, 360.0, 6.0), Ladar.centered(64, 1.6 / 64).bin_edges)
GLINT = SandfordRobertson(0.1, 0.4, 0.2, 0.02)
PRISM = Scene([Disk((0.1, 0.0), 0.5, GLINT, name="disk")]).tessellate(256)
#: The kernel weighs each hit through its material's θ table (16385 points), the mesh model
#: evaluates the BRDF at each hit: they agree to the table's interpolation.
TABLE_RTOL = 1e-3


def _counts(values, level, seed):
    """Seeded Poisson counts with ``level`` in the brightest bin, as a Sinogram (data units)
    and the counts per unit."""
    k = level / values.max()
    y = np.random.default_rng(seed).poisson(values * k) / k
    return ml.Sinogram(y, angles_deg=LAD.angles_deg, bin_edges=LAD.bin_edges,
                       info={"radiometry": "paper"}), k


def test_a_mesh_scenes_kernel_is_the_mesh_models_sum():
    """coating_kernel(scene, ladar) traces the mesh with the given options and predicts
    what simulate's compiled loop gives at the same rays per bin width, for the traced
    coating and another one."""
    K = coating_kernel(PRISM, LAD, samples=16, normals="exact")
    assert K.source == "mesh" and K.samples == pytest.approx(16.0)
    other = SandfordRobertson(0.3, 0.1, 0.5, 0.1)
    recoated = Scene([Disk((0.1, 0.0), 0.5, other, name="disk")]).tessellate(256)
    for mats, scene in (((GLINT,), PRISM), ((other,), recoated)):
        ref = ml.simulate(scene, LAD, model="mesh", rays_per_bin=16, normals="exact").values
        got = K.predict(mats)
        assert np.linalg.norm(got - ref) / np.linalg.norm(ref) < TABLE_RTOL


def test_resampling_a_mesh_kernel_traces_it_again_at_the_finer_spacing():
    """resampled(2N) halves the ray spacing (twice the rays of a slice), keeps the trace
    options, and a second call returns the kept kernel."""
    K = coating_kernel(PRISM, LAD, samples=8, normals="exact")
    K2 = K.resampled(16)
    assert K2.samples == pytest.approx(16.0) and K2.info["normals"] == "exact"
    assert K2.rays == pytest.approx(2 * K.rays, rel=0.01)
    assert K.resampled(16) is K2
    hits = ml.trace(PRISM, LAD)
    with pytest.raises(ParameterError, match=r"^only a kernel traced from its Scene"):
        coating_kernel(hits).resampled(16)


@pytest.mark.parametrize("call, message", [
    (lambda: coating_kernel(PRISM, LAD, ray_spacing=0.01),
     r"^coating_kernel takes the trace options .*got \['ray_spacing'\] \(the ray spacing "
     r"is samples="),
    (lambda: coating_kernel(ml.trace(PRISM, LAD), LAD),
     r"^Hits carry their ladar and rays"),
    (lambda: coating_kernel(Scene([Disk((0, 0), 0.5, GLINT)]), LAD, normals="smooth"),
     r"^trace options \['normals'\] apply to a mesh scene"),
    (lambda: coating_kernel(PRISM, LAD, samples=0.0), r"^samples must be"),
])
def test_bad_kernel_requests_are_refused_before_tracing(call, message):
    with pytest.raises(ParameterError, match=message):
        call()


def test_a_fit_on_a_mesh_scene_refines_and_reports_its_kernel():
    """fit_coatings on the mesh Scene traces it, climbs in rays per bin width until the
    parameters' shift (scaled by the order-1/2 factor) is within kernel_tol or the cap
    stops it with a warning, reports both, and its covariance exceeds the inverse Fisher
    information by the kernel's systematic term."""
    data = ml.simulate(PRISM, LAD, model="mesh", rays_per_bin=256).values
    measured, k = _counts(data, 1e4, 0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ml.fit.KernelErrorWarning)
        fit = fit_coatings(PRISM, measured, noise="poisson", photons_per_unit=k)
    capped = [w for w in caught if issubclass(w.category, ml.fit.KernelErrorWarning)]
    assert fit.info["source"] == "mesh" and fit.samples >= 16
    assert fit.kernel_error is not None and fit.info["kernel_shift"] is not None
    assert "rays per bin width" in repr(fit) and f"{MESH_ERROR_FACTOR:.3g}" in \
        fit.info["kernel_error_note"]
    assert (fit.info["kernel_shift"] <= 0.1) == (not capped)
    if capped:
        assert "rays per bin width would do" in str(capped[0].message)
    # the same kernel and data without the check: the Fisher σ alone is smaller
    bare = fit_coatings(coating_kernel(PRISM, LAD, samples=fit.samples), measured,
                        noise="poisson", photons_per_unit=k, kernel_tol=None)
    assert np.all(np.abs(bare.estimate - fit.estimate) < 0.01 * bare.stderr)
    assert np.all(fit.stderr >= bare.stderr) and np.any(fit.stderr > bare.stderr)


def test_a_kernel_of_the_users_hits_is_used_as_given_and_says_so():
    hits = ml.trace(PRISM, LAD)
    data = ml.simulate(PRISM, LAD, model="mesh", rays_per_bin=64).values
    measured, k = _counts(data, 1e4, 1)
    fit = fit_coatings(coating_kernel(hits), measured, noise="poisson", photons_per_unit=k)
    assert fit.kernel_error is None
    assert "give fit_coatings the mesh Scene" in fit.info["kernel_error_note"]
