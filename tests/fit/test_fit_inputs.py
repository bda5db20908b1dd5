"""What fit_coatings takes and refuses (meshladar.fit), from a user trial: a built-in
coating's parameter at the edge of its valid range (bounded by the class's own range, its
Jacobian column stepped the valid way: closed forms of the table's derivatives, and fits of
data from the analytic model plus seeded Poisson counts whose intervals hold the truth); a
kernel whose views, bins or radiometry are not the data's; unknown keys of ``free`` and
``bounds``; and a KernelErrorWarning's advice within what max_samples takes."""

from __future__ import annotations

import dataclasses
import math
import re
import warnings

import numpy as np
import pytest
from scipy.sparse import identity

import meshladar as ml
from meshladar import materials
from meshladar.brdf import BRDF, GGX, Lambertian, Phong, SandfordRobertson
from meshladar.errors import ParameterError
from meshladar.fit import (IdentifiabilityWarning, KernelErrorWarning, coating_kernel,
                           fit_coatings)
from meshladar.fit import coatings as coatings_module
from meshladar.fit._params import VALID_RANGES, _jacobian, _Param
from meshladar.fit._resolution import Ladder
from meshladar.fit._tables import GRID, _table
from meshladar.fit.kernels import MAX_KERNEL_SAMPLES
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk
from meshladar.waveforms import GaussianPulse, receive

#: The trial's ladar: 60 views of 64 bins.
LAD = Ladar(np.arange(0.0, 360.0, 6.0), np.linspace(-0.8, 0.8, 65))
#: Photoelectrons in the brightest bin.
PEAK = 1e4
#: A table derivative's one-sided step against the closed form, relative to its largest
#: value (the step is 1e-7 of the value: a linear parameter's error is round-off, ~1e-9;
#: the Phong exponent's second-order term, ~1e-6).
DERIVATIVE_TOL = 1e-5
#: The 95 % normal interval's level; and the most σ an estimate resting on a bound (its
#: likelihood's optimum beyond it) may sit from the truth.
LEVEL = 0.95
BOUND_Z = 3.0
#: θ of the tables' grid, as documented: (π/2) u², u evenly spaced on [0, 1].
THETA = 0.5 * math.pi * np.linspace(0.0, 1.0, GRID) ** 2


def _disk(material):
    return Scene([Disk((0.2, -0.1), 0.4, material, name="disk")])


def _counts(truth, seed=0, ladar=LAD):
    """(measured Sinogram, counts per unit): the analytic model of ``truth`` on a disk,
    PEAK photoelectrons in the brightest bin, Poisson counts of ``seed``."""
    exact = ml.simulate(_disk(truth), ladar).values
    k = PEAK / exact.max()
    y = np.random.default_rng(seed).poisson(exact * k) / k
    return ml.Sinogram(y, angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges), k


def _inside(fit, truth):
    """Whether each fitted parameter's LEVEL interval holds ``truth``'s value."""
    lo, hi = fit.interval(LEVEL)
    values = np.array([getattr(truth, n.split(".")[1]) for n in fit.names])
    return (lo <= values) & (values <= hi)


# -- the valid ranges -----------------------------------------------------------------------

_BASES = {SandfordRobertson: SandfordRobertson(0.0, 0.0, 0.0, 0.05, lobes="diffuse"),
          Lambertian: Lambertian(0.5), Phong: Phong(0.0, 0.0, 1.0), GGX: GGX(0.5, 0.5)}


@pytest.mark.parametrize("cls, name, low, high",
                         [(c, n, lo, hi) for c, r in VALID_RANGES for n, (lo, hi) in r.items()])
def test_each_range_is_the_classes_own(cls, name, low, high):
    """Each built-in field's bounds are valid at both (finite) ends and the class refuses
    a value just beyond, but for SR's e (the fit starts at 1e-4, the class at 1e-12) and
    Phong's exponent above (the class caps it at 1e6, the fit leaves it open)."""
    base = _BASES[cls]
    if not math.isfinite(high):
        assert (cls, name, high) == (Phong, "exponent", math.inf)
        assert dataclasses.replace(base, exponent=1e6).exponent == 1e6
        high = 1e6
    for v in (low, high):
        assert getattr(dataclasses.replace(base, **{name: v}), name) == v
    for v, inside in ((low - 1e-9 * max(1.0, abs(low)), cls is SandfordRobertson
                       and name == "e"), (high * (1 + 1e-9) + 1e-12, False)):
        if inside:
            dataclasses.replace(base, **{name: v})
        else:
            with pytest.raises(ParameterError, match=name):
                dataclasses.replace(base, **{name: v})


def _table_jacobian(material, names):
    """The Jacobian of ``material``'s table in ``names`` (identity kernel, unit scale)."""
    params = [_Param(0, n, *dict(VALID_RANGES)[type(material)][n]) for n in names]
    x = np.array([getattr(material, n) for n in names])
    return _jacobian({0: identity(GRID, format="csr")}, [material], params, x,
                     {0: _table(material)}, 1.0, GRID)


def test_a_step_out_of_the_valid_set_is_taken_the_other_way():
    """Phong with kd + ks = 1 (a step up in either leaves energy conservation) and GGX at
    reflectance 1 (its bound): every column is the closed form, cos θ/π for kd,
    (n + 2)/(2π) cos^n 2θ cos θ for ks, ks/(2π) cos^n 2θ (1 + (n + 2) ln cos 2θ) cos θ for
    n (0 where cos 2θ ≤ 0), and the table over R for GGX's reflectance (they were 0)."""
    c, c2 = np.cos(THETA), np.cos(2.0 * THETA)
    lobe = np.where(c2 > 0, np.abs(c2), 1.0)
    J = _table_jacobian(Phong(0.5, 0.5, 30.0), ("kd", "ks", "exponent"))
    expected = np.stack([c / math.pi,
                         np.where(c2 > 0, 32.0 / (2 * math.pi) * lobe ** 30 * c, 0.0),
                         np.where(c2 > 0, 0.5 / (2 * math.pi) * lobe ** 30
                                  * (1.0 + 32.0 * np.log(lobe)) * c, 0.0)], axis=1)
    for j in range(3):
        scale = np.abs(expected[:, j]).max()
        assert np.abs(J[:, j] - expected[:, j]).max() < DERIVATIVE_TOL * scale, j
    ggx = GGX(0.2, 1.0)
    J = _table_jacobian(ggx, ("alpha", "reflectance"))
    assert np.abs(J[:, 1] - _table(ggx)).max() < DERIVATIVE_TOL * _table(ggx).max()
    assert np.abs(J[:, 0]).max() > 0


# -- fits at the edge of the valid range ------------------------------------------------------

@pytest.mark.parametrize("truth, start", [(GGX(0.2, 0.8), GGX(0.25)),
                                          (Lambertian(0.7), Lambertian(1.0)),
                                          (Phong(0.5, 0.5, 30.0), Phong(0.5, 0.5, 30.0))],
                         ids=["ggx from reflectance 1", "lambertian from 1",
                              "phong kd + ks = 1"])
def test_a_start_on_the_edge_recovers_the_truth(truth, start):
    """The trial's cases: started (or true) on the edge of the valid set, every parameter
    is determined and its 95 % interval holds the truth (before: GGX's α = 0.2265 ±
    0.0002 with R frozen at 1, the albedo frozen at 1, Phong's kd and ks both "the data do
    not depend on it")."""
    measured, k = _counts(truth)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = fit_coatings(_disk(start), measured, noise="poisson", photons_per_unit=k)
    assert fit.undetermined == () and np.all(np.isfinite(fit.stderr))
    assert np.all(_inside(fit, truth)), (fit.estimate, fit.stderr)


def test_a_truth_at_zero_is_measured():
    """Phong with kd = 0 (its lower bound): kd's σ is finite (before: inf, "the data do
    not depend on it"), named weakly determined only because its estimate rests at 0,
    and every interval holds the truth."""
    truth = Phong(0.0, 0.8, 20.0)
    measured, k = _counts(truth)
    with pytest.warns(IdentifiabilityWarning, match=r"disk\.kd \(its uncertainty"):
        fit = fit_coatings(_disk(truth), measured, noise="poisson", photons_per_unit=k)
    assert np.all(np.isfinite(fit.stderr)) and 0.0 <= fit.estimate[0] < 1e-4
    assert "do not depend" not in fit.identifiable["disk.kd"]
    assert np.all(_inside(fit, truth))


def test_a_narrow_glints_estimate_on_its_bound_keeps_a_sigma():
    """GGX(0.002, 0.7), seed 1: the likelihood's optimum lies beyond R = 1, so the estimate
    rests there; R's σ is finite (before: R = 1 ± inf, "the data do not depend on it", and
    α's σ 3.7e-6, conditional on R), each truth within BOUND_Z σ, and the ridge α ∝ R is
    named with the truth's combination inside its 95 % interval."""
    truth = GGX(0.002, 0.7)
    measured, k = _counts(truth, seed=1)
    fit = fit_coatings(_disk(GGX(0.0025, 0.9)), measured, noise="poisson",
                       photons_per_unit=k)
    assert np.all(np.isfinite(fit.stderr)) and fit.stderr[0] > 1e-4
    assert fit.estimate[1] == pytest.approx(1.0, abs=1e-9) and 0.1 < fit.stderr[1] < 0.2
    assert np.all(np.abs(fit.estimate - [0.002, 0.7]) < BOUND_Z * fit.stderr)
    coefficients = fit.info["combination_coefficients"]
    (_, value, sigma), = fit.combinations
    assert abs(coefficients[0] @ [0.002, 0.7] - value) < 1.96 * sigma


@dataclasses.dataclass(frozen=True)
class _Tilted(BRDF):
    """A user's model: F cos θ = (albedo + slope (cos θ − 1/2)) cos θ / π."""

    albedo: float
    slope: float

    def projected(self, cos_theta, sin_theta):
        c = np.maximum(cos_theta, 0.0)
        return (self.albedo + self.slope * (c - 0.5)) * c / math.pi


#: The σ of a fit against the inverse Fisher information of the analytic model at the
#: estimate (measured: 3e-6).
SIGMA_TOL = 1e-4


def test_an_unbounded_parameter_at_zero_is_not_dead():
    """A user's parameter bounded only below (the slope, ≥ 0) whose truth is 0: on seed 2
    its estimate rests at 0, and it is measured, its σ the inverse Fisher information of
    Poisson counts of the analytic model (linear in both parameters) to SIGMA_TOL (before:
    scaled by 1e-12, σ = inf and "the data do not depend on it")."""
    truth = _Tilted(0.5, 0.0)
    measured, k = _counts(truth, seed=2)
    with pytest.warns(IdentifiabilityWarning, match=r"disk\.slope \(its uncertainty .* "
                                                    r"exceeds half its value"):
        fit = fit_coatings(_disk(truth), measured, noise="poisson", photons_per_unit=k,
                           bounds={"slope": (0.0, math.inf)})
    assert fit.estimate[1] < 1e-12 and "do not depend" not in fit.identifiable["disk.slope"]
    a = ml.simulate(_disk(_Tilted(1.0, 0.0)), LAD).values.ravel()
    b = ml.simulate(_disk(_Tilted(0.5, 1.0)), LAD).values.ravel() - 0.5 * a
    m = k * (fit.estimate[0] * a + fit.estimate[1] * b)
    D = k * np.stack([a, b], axis=1)
    ok = m > 0
    fisher = D[ok].T @ (D[ok] / m[ok, None])
    np.testing.assert_allclose(fit.stderr, np.sqrt(np.diag(np.linalg.inv(fisher))),
                               rtol=SIGMA_TOL)
    assert np.all(_inside(fit, truth))


# -- data the kernel was not made for ---------------------------------------------------------

def _kernel():
    return coating_kernel(_disk(Lambertian(0.5)), LAD, samples=256)


@pytest.mark.parametrize("what, ladar, radiometry", [
    ("angles_deg", Ladar(LAD.angles_deg + 90.0, LAD.bin_edges), None),
    ("bin_edges", Ladar(LAD.angles_deg, np.linspace(-0.4, 0.4, 65)), None),
    ("radiometry", LAD, "power")])
def test_data_of_other_views_bins_or_radiometry_are_refused(what, ladar, radiometry):
    """A kernel of LAD fitted to data of the same shape but other views, bin edges or
    radiometry is refused, naming what differs and both values (before: a fit, ρ = 0.08
    for 0.5 with the views turned)."""
    sino = ml.simulate(_disk(Lambertian(0.5)), ladar, radiometry=radiometry or "paper")
    values = {"angles_deg": r"90\.0 in measured, 0\.0 in the kernel",
              "bin_edges": r"-0\.4 in measured, -0\.8 in the kernel",
              "radiometry": r"radiometry 'power', the kernel's is 'paper'"}[what]
    with pytest.raises(ParameterError, match=values):
        fit_coatings(_kernel(), sino)


def test_data_that_agree_or_do_not_say_are_fitted():
    """Angles 360° apart are the same views; a hand-made Sinogram without a radiometry is
    not refused on it."""
    y = ml.simulate(_disk(Lambertian(0.5)), LAD).values
    fit = fit_coatings(_kernel(), ml.Sinogram(y, angles_deg=LAD.angles_deg + 360.0,
                                              bin_edges=LAD.bin_edges), kernel_tol=None)
    assert fit.estimate[0] == pytest.approx(0.5, abs=1e-3)


def test_hits_and_waveforms_of_other_views_are_refused():
    """Hits traced on views off the data's (the same azimuths, other elevations) are
    refused on their view vectors, as a kernel of them is; waveforms of another standoff
    on their time edges."""
    scene = Scene([Disk((0.0, 0.0), 0.5, materials.DARK_GRAY, name="disk")]).tessellate(32)
    az = np.deg2rad(np.arange(0.0, 360.0, 90.0))
    views = np.stack([np.cos(az), np.sin(az), np.full(4, 0.5)], axis=1)
    hits = ml.trace(scene, Ladar(None, LAD.bin_edges, view_vectors=views))
    flat = ml.Sinogram(np.ones((4, 64)), angles_deg=np.rad2deg(az), bin_edges=LAD.bin_edges)
    for geometry in (hits, coating_kernel(hits)):
        with pytest.raises(ParameterError, match="view_vectors differ"):
            fit_coatings(geometry, flat)
    kernel = coating_kernel(_disk(Lambertian(0.5)), Ladar(LAD.angles_deg[:6], LAD.bin_edges),
                            samples=64)
    far = receive(kernel.sinogram(), sample_rate=10e9, pulse=GaussianPulse(5e-10),
                  standoff=1.0)
    with pytest.raises(ParameterError, match="time_edges differ"):
        fit_coatings(kernel.received(10e9, pulse=GaussianPulse(5e-10)), far)


# -- unknown names in free and bounds ---------------------------------------------------------

PAIR = ml.phantoms.scene("disk_pair", large=materials.DARK_GRAY, small=materials.ALUMINUM)


@pytest.mark.parametrize("kwargs, message", [
    (dict(free={"large": ["rho_d"], "smal": ["e"]}),
     r"^free's parts must be among \['large', 'small'\] \(or an index below 2\); "
     r"got \['smal'\]$"),
    (dict(free={"large": ["rho_d"]}, bounds={"large.rhod": (0.0, 0.01)}),
     r"^bounds' keys must name free parameters, among \['large\.rho_d', 'rho_d'\] "
     r"\(or 'index\.param', e\.g\. '0\.rho_d'\); got \['large\.rhod'\]$"),
    (dict(parts=["large"], free={"small": ["e"]}), r"^free names part 'small', which parts="),
    (dict(free=["rho_d"], bounds={"b": (0.0, 0.5)}), r"got \['b'\]$")])
def test_unknown_names_are_refused_before_tracing(kwargs, message, monkeypatch):
    """The trial's free and bounds with a misspelt part or parameter (silently ignored
    before) are refused, the unknown key named and the valid ones listed, before the
    scene is traced."""
    def traced(*args, **kw):
        raise AssertionError("traced before the arguments were checked")
    monkeypatch.setattr(coatings_module, "coating_kernel", traced)
    sino = ml.Sinogram(np.ones((60, 64)), angles_deg=LAD.angles_deg, bin_edges=LAD.bin_edges)
    with pytest.raises(ParameterError, match=message):
        fit_coatings(PAIR, sino, **kwargs)


def test_bounds_of_a_phong_fit_are_checked():
    """bounds={"kdd": ...} on a Phong fit names the valid keys; bounds past a built-in
    field's valid range are refused with it."""
    kernel = coating_kernel(_disk(Phong(0.2, 0.5, 30.0)), LAD, samples=64)
    sino = kernel.sinogram()
    with pytest.raises(ParameterError, match=r"among \['disk\.kd', 'disk\.ks', "
                                             r"'disk\.exponent', 'kd', 'ks', 'exponent'\].*"
                                             r"got \['kdd'\]"):
        fit_coatings(kernel, sino, bounds={"kdd": (0.0, 1.0)})
    with pytest.raises(ParameterError, match=r"disk\.ks must lie in its valid range "
                                             r"\[0, 1\]; got \(0, 2\)"):
        fit_coatings(kernel, sino, bounds={"ks": (0.0, 2.0)})


# -- the kernel error's advice ----------------------------------------------------------------

class _Stub:
    """An analytic kernel of ``samples`` pieces (what Ladder reads)."""

    source, _traced = "analytic", ()

    def __init__(self, samples):
        self.samples = samples

    def resampled(self, samples):
        return _Stub(samples)


def _advice(n, worst, tol=0.1):
    """The KernelErrorWarning of a ladder stopped with ``n`` samples and error ``worst``."""
    ladder = Ladder(_Stub(n // 2), tol, n)
    ladder.error, ladder.shift = worst, 0.0
    with pytest.warns(KernelErrorWarning) as caught:
        ladder.warn_if_coarse()
    return str(caught[0].message)


def _asked(text):
    return [int(v) for v in re.findall(r"max_samples=(\d+)", text)]


def test_the_advice_stays_within_max_samples():
    """The trial's 144 σ at 2^16 samples asked for 4194304, which max_samples refuses: now
    at most 2^20, with the error expected there (144 / 4^4 = 0.5625 σ, ~4× per doubling)
    and the kernel_tol that accepts it; at 2^20 itself, how to accept it; 0.426 σ still
    asks for 2^16 · 4 (the error falls ~4× per doubling)."""
    text = _advice(2 ** 16, 144.0)
    assert max(_asked(text)) == MAX_KERNEL_SAMPLES
    assert f"max_samples={MAX_KERNEL_SAMPLES} with kernel_tol=0.57" in text
    assert "0.56 σ" in text
    text = _advice(MAX_KERNEL_SAMPLES, 3.0)
    assert max(_asked(text)) <= MAX_KERNEL_SAMPLES and "kernel_tol=3 allows it" in text
    assert _asked(_advice(2 ** 16, 0.426))[-1] == 2 ** 18


def test_a_fits_advice_is_taken():
    """A noiseless fit (σ from the residuals, at round-off) stopped at 128 samples with
    kernel_tol=1e-6, hundreds of σ off, which 2^20 samples would not bring within it: the
    max_samples it advises is the most fit_coatings takes, and it takes it."""
    scene = _disk(Lambertian(0.5))
    with pytest.warns(KernelErrorWarning) as caught:
        fit_coatings(scene, ml.simulate(scene, LAD), samples=64, max_samples=128,
                     kernel_tol=1e-6)
    asked = _asked(str(caught[0].message))
    assert asked == [128, MAX_KERNEL_SAMPLES]
    fit = fit_coatings(scene, ml.simulate(scene, LAD), samples=64, max_samples=max(asked),
                       kernel_tol=None)
    assert fit.estimate[0] == pytest.approx(0.5, abs=1e-3)
