"""Coverage of coating fits on INDEPENDENT data (meshladar.fit): the analytic model's exact
profiles (not the fit's kernel) with seeded Poisson noise at 10³, 10⁴, 10⁵ and 10⁶
photoelectrons in the brightest bin, on a diffuse coating and a glinting one (e = 0.02),
400 seeded trials per scene, and on the paper's gray/aluminium pair (e = 0.007) at 10⁵ and
10⁶ (200 trials) and, on demand (``pytest -m exhaustive``), at 10⁴ with profile intervals
(200 trials), and on 120 views at 10⁴ the bias-corrected estimates (200 trials); and on a
mesh, its data from the mesh model at a finer spacing."""

from __future__ import annotations

import multiprocessing
import os
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import meshladar as ml
from meshladar import materials
from meshladar.brdf import SandfordRobertson
from meshladar.fit import coating_kernel, fit_coatings
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk
from meshladar.studies import paper

LAD = Ladar(np.arange(0.0, 360.0, 6.0), Ladar.centered(64, 1.6 / 64).bin_edges)
SCENES = {
    "diffuse": Scene([Disk((0.1, 0.0), 0.5, SandfordRobertson(0.4, 0.0, 0.5, 1.0,
                                                              lobes="diffuse"), name="disk")]),
    "glint": Scene([Disk((0.1, 0.0), 0.5, SandfordRobertson(0.1, 0.4, 0.2, 0.02),
                         name="disk")]),
    "pair": paper._pair(materials.DARK_GRAY, materials.ALUMINUM),
}
LEVELS = (1e3, 1e4, 1e5, 1e6)
#: The pair at 10⁵ and 10⁶: at 10³ photoelectrons in the aluminium glint's bin the fit
#: itself calls the aluminium's ε undetermined (σ beyond half its range;
#: test_the_pair_at_1e3_names_what_it_cannot_determine), so no interval is claimed; at 10⁴
#: it calls the aluminium's ε or e weakly determined in most trials, and the profile
#: intervals that cover there take an hour of CPU: that level runs on demand (see
#: ASSERTED).
LEVELS_OF = {"diffuse": LEVELS, "glint": LEVELS, "pair": LEVELS[2:]}
#: Seeded trials per scene and photon level (100 × 4 levels × 2 scenes = 800 asserted).
TRIALS = 100
#: The goals: coverage ≥ 0.90 and |mean bias| < 0.25 σ. A coverage measured on N trials
#: has a binomial sampling error of sqrt(0.9 × 0.1 / N) at 0.90 (0.03 on 100 trials): it is
#: asserted to be no more than SAMPLING_SIGMAS of them below the goal, per level and pooled
#: over the four levels (0.84 and 0.87), so a true coverage of 0.90 passes and one of 0.80
#: fails at any level.
MIN_COVERAGE = 0.90
SAMPLING_SIGMAS = 2.0
MAX_BIAS = 0.25


def _floor(n):
    """The lowest measured coverage on ``n`` trials consistent with MIN_COVERAGE."""
    return MIN_COVERAGE - SAMPLING_SIGMAS * np.sqrt(MIN_COVERAGE * (1 - MIN_COVERAGE) / n)


#: One BLAS thread a worker: the trials fill every core with processes, and each one's own
#: BLAS threads on top oversubscribe them (the 120-view trials on 2 cores: 335 s with the
#: default threads, 230 s with one).
ONE_THREAD = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _on_every_core(work, trials, monkeypatch):
    """``work`` (a function of a range of seeds) on every core, the ``trials`` seeds dealt
    round-robin, one BLAS thread a worker: the list of its results."""
    for name in ONE_THREAD:
        monkeypatch.setenv(name, "1")
    cores = len(os.sched_getaffinity(0))
    with ProcessPoolExecutor(cores, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(work, [range(i, trials, cores) for i in range(cores)]))


def _seeded_fit(scene, kernel, exact, k, seed, lad=LAD):
    """(fit, true values of its parameters) of the exact profiles ``exact`` (on ``lad``'s
    views and bins) with seeded Poisson noise at ``k`` counts per unit, started from the
    truth."""
    y = np.random.default_rng(seed).poisson(exact * k) / k
    measured = ml.Sinogram(y, angles_deg=lad.angles_deg, bin_edges=lad.bin_edges,
                           info={"radiometry": "paper"})
    with warnings.catch_warnings():
        # a weakly determined parameter at 10³ photons is named; it keeps its σ
        warnings.simplefilter("ignore", ml.fit.IdentifiabilityWarning)
        # a mesh kernel capped above kernel_tol says so; its error is in σ
        warnings.simplefilter("ignore", ml.fit.KernelErrorWarning)
        fit = fit_coatings(kernel, measured, noise="poisson", photons_per_unit=k)
    true = np.array([getattr(scene.shapes[kernel.part_index(n.split(".")[0])].material,
                             n.split(".")[1]) for n in fit.names])
    return fit, true


def _trials(scene, levels=LEVELS, trials=TRIALS, mesh=False, profile=()):
    """Per level, (inside (trials, n) bool, z (trials, n), kernel errors, determined
    (trials, n) bool, half-widths (trials, n)) of the 95 % intervals against the truth
    (``trials``: a count, or the seeds); the exact profiles computed
    once (``mesh``: the mesh model at MESH_DATA_RAYS rays per bin width), the kernel traced
    once (its refinements kept), every fit started from the truth; the parameters named
    in ``profile`` get profile-likelihood intervals, the others normal ones."""
    if mesh:
        exact = ml.simulate(scene, LAD, model="mesh", rays_per_bin=MESH_DATA_RAYS,
                            normals="exact").values
        kernel = coating_kernel(scene, LAD, normals="exact")
    else:
        exact = ml.simulate(scene, LAD, model="analytic").values
        kernel = coating_kernel(scene, LAD, samples=2048)
    out = {}
    for level in levels:
        k = level / exact.max()
        inside, z, kerr, known, half = [], [], [], [], []
        for seed in range(trials) if isinstance(trials, int) else trials:
            fit, true = _seeded_fit(scene, kernel, exact, k, seed)
            lo, hi = fit.interval(0.95, method="profile", parameters=list(profile))
            inside.append((lo <= true) & (true <= hi))
            half.append(0.5 * (hi - lo))
            z.append((fit.estimate - true) / fit.stderr)
            kerr.append(fit.info["kernel_shift"] if mesh
                        else max(fit.kernel_error, fit.info["kernel_shift"]))
            known.append([fit.identifiable[n] is True for n in fit.names])
        out[level] = (np.array(inside), np.array(z), np.array(kerr), np.array(known),
                      np.array(half))
    return fit.names, out


#: The scenes whose coverage is asserted (the pair at 10⁵-10⁶, 200 fits in ~80 s; measured
#: 2026-12-03, 100 trials a level: coverage 0.90-1.00 per parameter and level, |bias| ≤
#: 0.19 σ per level). At 10⁴ the aluminium's ε and e spread 2.6 and 3.1 Fisher σ with
#: heavy tails (their normal intervals cover 0.91 and 0.90 of 200 trials, at the goal's
#: edge): that level is asserted with profile intervals for those two, on demand
#: (test_the_pair_at_1e4_covers_the_truth_with_profile_intervals).
ASSERTED = ("diffuse", "glint", "pair")


@pytest.mark.slow
@pytest.mark.parametrize("name", ASSERTED)
def test_intervals_cover_the_truth_on_exact_data(name):
    """Every parameter's mean bias over the scene's trials is below 0.25 σ; its 95 %
    interval holds the truth in ≥ 90 % of the trials at each photon level and pooled
    (within the sampling error, _floor); the kernel error and the shift it causes stay
    ≤ 0.1 σ in every trial (the fit refines the kernel)."""
    levels = LEVELS_OF[name]
    names, out = _trials(SCENES[name], levels)
    z = np.concatenate([out[lv][1] for lv in levels])
    inside = np.concatenate([out[lv][0] for lv in levels])
    report = {lv: (np.round(out[lv][0].mean(0), 2), np.round(out[lv][1].mean(0), 2))
              for lv in levels}
    bias = z.mean(axis=0)
    assert np.all(np.abs(bias) < MAX_BIAS), (dict(zip(names, bias)), report)
    for lv in levels:
        cover = out[lv][0].mean(axis=0)
        assert np.all(cover >= _floor(TRIALS)), (lv, dict(zip(names, cover)), report)
    assert np.all(inside.mean(axis=0) >= _floor(len(inside))), report
    assert max(out[lv][2].max() for lv in levels) <= 0.1


@pytest.mark.slow
def test_the_pair_at_1e3_names_what_it_cannot_determine():
    """At 10³ photoelectrons in the aluminium glint's bin, the pair's fit names the
    aluminium's ε as not determined (in each of three seeded trials) rather than claim an
    interval for it."""
    scene = SCENES["pair"]
    exact = ml.simulate(scene, LAD, model="analytic").values
    k = 1e3 / exact.max()
    for seed in range(3):
        y = np.random.default_rng(seed).poisson(exact * k) / k
        measured = ml.Sinogram(y, angles_deg=LAD.angles_deg, bin_edges=LAD.bin_edges,
                               info={"radiometry": "paper"})
        with pytest.warns(ml.fit.IdentifiabilityWarning, match=r"small\.epsilon"):
            fit = fit_coatings(scene, measured, noise="poisson", photons_per_unit=k)
        assert fit.identifiable["small.epsilon"] is not True


#: The pair at 10⁴ photoelectrons, the aluminium's ε and e with profile-likelihood intervals
#: (their estimates spread 2.6 and 3.1 Fisher σ: the likelihood is far from quadratic there),
#: the other six with normal ones: seeded trials, on demand (``pytest -m exhaustive``),
#: spread over every core (about an hour of CPU). Measured 2026-12-04 on these 200 trials:
#: coverage 0.91-0.965 (the aluminium's ε and e 0.965), mean bias of the six ≤ 0.21 σ,
#: median bias of the profiled two +0.20 and −0.17 σ (their mean +0.42 and −0.48 σ,
#: heavy-tailed: spread 2.6 and 3.1 σ): the estimates fall in two basins along the
#: ridge (see WIDE_LAD).
PAIR_1E4_TRIALS = 200
PAIR_1E4_PROFILED = ("small.epsilon", "small.e")


def _pair_1e4(seeds):
    """One worker's share of the pair's trials at 10⁴ photoelectrons (see _trials)."""
    names, out = _trials(SCENES["pair"], [1e4], seeds, profile=PAIR_1E4_PROFILED)
    return names, out[1e4]


@pytest.mark.slow
@pytest.mark.exhaustive
def test_the_pair_at_1e4_covers_the_truth_with_profile_intervals(monkeypatch):
    """The paper's pair at 10⁴ photoelectrons over PAIR_1E4_TRIALS seeded trials: every
    parameter's 95 % interval (profile likelihood for the aluminium's ε and e, normal for
    the rest) covers the truth in ≥ 90 % of them within the sampling error (_floor). The
    six parameters with normal intervals have |mean bias| < 0.25 σ; the two profiled ones,
    whose estimates spread four to five times their normal σ (a heavy-tailed, far from
    normal likelihood), have |median bias| < 0.25 σ (their mean is ±0.5 σ)."""
    parts = _on_every_core(_pair_1e4, PAIR_1E4_TRIALS, monkeypatch)
    names = parts[0][0]
    inside = np.concatenate([p[1][0] for p in parts])
    assert len(inside) == PAIR_1E4_TRIALS
    z = np.concatenate([p[1][1] for p in parts])
    cover = dict(zip(names, np.round(inside.mean(axis=0), 3)))
    assert np.all(inside.mean(axis=0) >= _floor(PAIR_1E4_TRIALS)), cover
    profiled = np.isin(names, PAIR_1E4_PROFILED)
    bias = np.where(profiled, np.median(z, axis=0), z.mean(axis=0))
    assert np.all(np.abs(bias) < MAX_BIAS), (dict(zip(names, np.round(bias, 2))), cover)


#: The pair at 10⁴ with normal intervals: the aluminium's ε and e lie on a ridge
#: (correlated at −0.997 to −0.999 in all but two of the 200 trials), each loose and
#: skewed (mean bias +0.42 and −0.48 σ), and the fit names the combination across it.
RIDGE_TRIALS = 200
RIDGE = ("small.epsilon", "small.e")


def _pair_ridge(seeds):
    """One worker's share of the pair's ridge trials at 10⁴ photoelectrons: per trial, the
    z of every parameter, whether its normal 95 % interval holds the truth, the z of the
    combination across the ridge (NaN when the fit names none), and whether the fit calls
    each parameter determined."""
    scene = SCENES["pair"]
    exact = ml.simulate(scene, LAD, model="analytic").values
    kernel = coating_kernel(scene, LAD, samples=2048)
    k = 1e4 / exact.max()
    rows = []
    for seed in seeds:
        fit, true = _seeded_fit(scene, kernel, exact, k, seed)
        lo, hi = fit.interval(0.95)
        ridge = [i for i, c in enumerate(fit.info["combination_coefficients"])
                 if set(np.array(fit.names)[c != 0]) == set(RIDGE)]
        zc = np.nan
        if ridge:
            (_, value, sigma), c = (fit.combinations[ridge[0]],
                                    fit.info["combination_coefficients"][ridge[0]])
            zc = (value - c @ true) / sigma
        rows.append(((fit.estimate - true) / fit.stderr, (lo <= true) & (true <= hi), zc,
                     [fit.identifiable[n] is True for n in fit.names]))
    return fit.names, rows


@pytest.mark.slow
def test_the_ridge_the_guide_shows():
    """The coatings guide's example, seed 0 of the ridge trials: the fit names
    0.01805·small.epsilon + small.e = 0.016633 ± 8.2e-05, whose truth is 0.016565."""
    scene = SCENES["pair"]
    exact = ml.simulate(scene, LAD, model="analytic").values
    fit, true = _seeded_fit(scene, coating_kernel(scene, LAD, samples=2048), exact,
                            1e4 / exact.max(), 0)
    (text, value, sigma), = fit.combinations
    assert text == "0.01805·small.epsilon + small.e"
    assert round(value, 6) == 0.016633 and f"{sigma:.2g}" == "8.2e-05"
    c, = fit.info["combination_coefficients"]
    assert round(float(c @ true), 6) == 0.016565


@pytest.mark.slow
def test_the_pair_at_1e4_names_the_ridge_and_measures_across_it(monkeypatch):
    """The paper's pair at 10⁴ photoelectrons over RIDGE_TRIALS seeded trials (on every
    core), normal intervals: the fit names the combination across the aluminium's ε-e
    ridge in at least 98 % of them, and that combination's mean bias is below 0.25 σ and
    its 95 % interval (value ∓ 1.96 σ) holds the truth's combination within the sampling
    error of 0.90 (_floor); the other six parameters have mean bias below 0.25 σ and
    cover as well; where the fit calls the aluminium's ε determined, its interval covers
    within the sampling error too. (Measured 2026-12-05: named in 198 of 200, mean bias
    −0.07 σ, spread 1.10 σ, coverage 0.91. 2026-12-06: ε called determined in 54 trials,
    covering 0.93 there, since both of a ridge's pair are weakly determined where either
    is loose; before, in 120 that covered 0.58. e is called determined in 52, covering
    0.77: not asserted, a ridge's normal intervals can mislead where both σ are within a
    quarter of their values.)"""
    parts = _on_every_core(_pair_ridge, RIDGE_TRIALS, monkeypatch)
    names = np.array(parts[0][0])
    rows = [r for p in parts for r in p[1]]
    assert len(rows) == RIDGE_TRIALS
    z = np.array([r[0] for r in rows])
    inside = np.array([r[1] for r in rows])
    zc = np.array([r[2] for r in rows])
    named = np.isfinite(zc)
    assert named.mean() >= 0.98, named.mean()
    cover = float(np.mean(np.abs(zc[named]) <= 1.959964))
    assert abs(zc[named].mean()) < MAX_BIAS and cover >= _floor(named.sum()), (
        zc[named].mean(), cover)
    known = np.array([r[3] for r in rows])
    eps = list(names).index(RIDGE[0])
    called = known[:, eps]
    assert called.any()
    assert inside[called, eps].mean() >= _floor(called.sum()), (called.sum(),
                                                               inside[called, eps].mean())
    others = ~np.isin(names, RIDGE)
    bias = z[:, others].mean(axis=0)
    assert np.all(np.abs(bias) < MAX_BIAS), dict(zip(names[others], bias))
    assert np.all(inside[:, others].mean(axis=0) >= _floor(RIDGE_TRIALS)), dict(
        zip(names[others], inside[:, others].mean(axis=0)))


#: The pair at 10⁴ on twice the views (3° apart: twice the data). On 60 views the maximum-
#: likelihood estimates of the aluminium's ε and e fall in two basins along their ridge
#: (ε ≈ 0.51, e ≈ 0.0074 and ε ≈ 0.82, e ≈ 0.0017, in 143 and 57 of 200 trials), so no
#: correction brings their mean within 0.25 σ (the first-order one: bias 0.40 → 0.29 of
#: the estimates' spread); on 120 views 11 of 200 reach the narrow basin, the estimate's
#: bias is ±0.24 of the spread (e: −0.30 σ) and the first-order correction brings every
#: parameter's within 0.22 σ (measured 2026-12-06).
WIDE_LAD = Ladar(np.arange(0.0, 360.0, 3.0), LAD.bin_edges)
WIDE_TRIALS = 200


def _pair_wide(seeds):
    """One worker's share of the pair's trials at 10⁴ photoelectrons on WIDE_LAD: per trial,
    the z of the estimate and of the bias-corrected estimate, and whether each parameter's
    normal 95 % interval holds the truth."""
    scene = SCENES["pair"]
    exact = ml.simulate(scene, WIDE_LAD, model="analytic").values
    kernel = coating_kernel(scene, WIDE_LAD, samples=2048)
    rows = []
    for seed in seeds:
        fit, true = _seeded_fit(scene, kernel, exact, 1e4 / exact.max(), seed, WIDE_LAD)
        lo, hi = fit.interval(0.95)
        rows.append(((fit.estimate - true) / fit.stderr, (fit.corrected - true) / fit.stderr,
                     (lo <= true) & (true <= hi)))
    return fit.names, rows


@pytest.mark.slow
def test_the_corrected_estimates_of_the_pair_at_1e4_are_unbiased(monkeypatch):
    """The paper's pair at 10⁴ photoelectrons on 120 views over WIDE_TRIALS seeded trials (on
    every core): the bias-corrected estimates (``fit.corrected``, the estimate less its
    first-order bias) of all eight parameters have |mean bias| < 0.25 σ, where the
    estimates themselves do not (the aluminium's e beyond it); the normal intervals cover
    the truth within the sampling error of 0.90 (_floor)."""
    parts = _on_every_core(_pair_wide, WIDE_TRIALS, monkeypatch)
    names = parts[0][0]
    rows = [r for p in parts for r in p[1]]
    assert len(rows) == WIDE_TRIALS
    z, zc, inside = (np.array([r[i] for r in rows]) for i in range(3))
    raw, corrected = dict(zip(names, z.mean(axis=0))), dict(zip(names, zc.mean(axis=0)))
    assert max(abs(v) for v in corrected.values()) < MAX_BIAS, (corrected, raw)
    assert abs(raw["small.e"]) > MAX_BIAS, raw
    cover = inside.mean(axis=0)
    assert np.all(cover >= _floor(WIDE_TRIALS)), dict(zip(names, cover))


#: The mesh model's data: 4096 rays per bin width, twice the most the kernel's refinement
#: reaches on this scene (2048, capped by MAX_KERNEL_RAYS), through simulate's own loop.
MESH_DATA_RAYS = 4096
#: Seeded trials per level on the mesh (50 × 4 levels = 200; ~1 s a fit).
MESH_TRIALS = 50


@pytest.mark.slow
def test_mesh_intervals_cover_the_truth_on_finer_mesh_data():
    """The glinting disk as a 256-sided prism (exact normals), fitted through its Scene (the
    kernel traced at 16 rays per bin width and refined): on the mesh model's profiles at
    a finer spacing plus Poisson noise, each parameter's interval covers the truth at each
    level and pooled (within the sampling error of 50 and 200 trials), with |bias| <
    0.25 σ pooled. At 10⁵-10⁶ photons the refinement stops at its ray cap with the shift
    above kernel_tol; the shift is then in σ (measured 2026-12-03, 40 trials a level:
    coverage 0.875-1.0, the shift 0.26 σ and 0.81 σ)."""
    scene = SCENES["glint"].tessellate(256)
    names, out = _trials(scene, LEVELS, MESH_TRIALS, mesh=True)
    z = np.concatenate([out[lv][1] for lv in LEVELS])
    inside = np.concatenate([out[lv][0] for lv in LEVELS])
    report = {lv: (np.round(out[lv][0].mean(0), 2), np.round(out[lv][1].mean(0), 2),
                   round(float(out[lv][2].max()), 2)) for lv in LEVELS}
    assert np.all(np.abs(z.mean(axis=0)) < MAX_BIAS), report
    for lv in LEVELS:
        assert np.all(out[lv][0].mean(axis=0) >= _floor(MESH_TRIALS)), (lv, report)
    assert np.all(inside.mean(axis=0) >= _floor(len(inside))), report


if __name__ == "__main__":
    # python tests/fit/test_coverage.py SCENE LEVEL TRIALS [PROFILED,...]: the coverage and
    # bias of each parameter's 95 % interval at one photon level (e.g. the pair at 10⁴ with
    # the aluminium's ε and e profiled: pair 1e4 100 small.epsilon,small.e)
    import sys
    import time

    scene_name, level, count = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    profiled = sys.argv[4].split(",") if len(sys.argv) > 4 else ()
    start = time.perf_counter()
    names, out = _trials(SCENES[scene_name], [level], count, profile=profiled)
    inside, z, _, known, _ = out[level]
    print(f"{scene_name} at {level:g} photoelectrons, {count} trials, "
          f"{time.perf_counter() - start:.0f} s; profiled: {', '.join(profiled) or 'none'}")
    for i, name in enumerate(names):
        print(f"  {name:16s} coverage {inside[:, i].mean():.2f}  bias {z[:, i].mean():+.2f} σ"
              f"  spread {z[:, i].std():.2f} σ  determined {known[:, i].mean():.2f}")
