"""Faceting studies, convergence orders, and the accuracy knob (tol)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import meshladar as ml
from meshladar import studies
from meshladar.studies import faceting
from meshladar.materials import ALUMINUM, DARK_GRAY, lambertian


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def test_flat_facets_on_a_lambertian_disk_converge_at_second_order():
    # With F constant every ray weighs ρd/π·δs whatever its normal, so flat facets err only
    # in position: the inscribed N-gon's ranges are off by at most R(1 − cos(π/N)) ≈
    # Rπ²/(2N²), and footprints return each flat facet's range interval exactly, so the
    # binned error falls as N⁻² (until the 8-rays-per-bin sampling floor, ~4e-3).
    scene = ml.phantoms.scene("disk", lambertian(1.0))
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0))
    exact = ml.simulate(scene, ladar)
    ns = [64, 128, 256]
    errs = [_rel(ml.simulate(scene.tessellate(n), ladar, model="mesh", normals="flat",
                             rays_per_bin=8, footprint=True).values, exact.values) for n in ns]
    order = -np.polyfit(np.log(ns), np.log(errs), 1)[0]
    assert order >= 1.6                                   # theory 2, measured 1.8


@pytest.fixture(scope="module")
def study():
    return studies.faceting_study("quick", phantoms=["disk"],
                                  coatings=["aluminum", "diffuse_b0.99"])


def _series(study, coating, series):
    rows = [r for r in study["rows"] if r["coating"] == coating and r["series"] == series]
    return sorted(rows, key=faceting._resolution)


@pytest.mark.slow
def test_study_separates_the_error_sources(study):
    # normal faceting: at equal segments exact normals beat flat ones for a glossy coating
    flat = _series(study, "aluminum", "normal")
    exact = _series(study, "aluminum", "position")
    for f, e in zip(flat, exact):
        assert e["rel_l2"] < f["rel_l2"] or f["segments"] <= 32
    # footprint beats point sampling at equal rays
    point = _series(study, "diffuse_b0.99", "rays")
    foot = _series(study, "diffuse_b0.99", "rays_footprint")
    for p, f in zip(point, foot):
        assert f["rel_l2"] < p["rel_l2"]
    # the pixel model's error falls with the pixel size
    pix = [r["rel_l2"] for r in _series(study, "diffuse_b0.99", "pixel")]
    assert pix[0] > pix[1] > pix[2]
    # reconstruction errors follow the sinogram errors
    assert flat[-1]["image_rel_l2"] < flat[0]["image_rel_l2"]


@pytest.mark.slow
def test_glint_regime_breaks_flat_facets_until_n_exceeds_pi_over_e(study):
    orders = {(o["coating"], o["series"]): o for o in study["orders"]}
    flat = orders[("aluminum", "normal")]
    # a facet's angular step 2π/N must fall below ~2e for the e = 0.007 lobe to be seen:
    # flat facets stay at O(1) error until N ≈ π/e ≈ 450
    assert flat["break_at"] >= 256 and flat["coarsest_rel_l2"] > 0.9
    # exact normals converge from the first refinements, at about second order
    pos = orders[("aluminum", "position")]
    assert pos["break_at"] <= 128 and pos["order"] > 1.3


@pytest.mark.slow
def test_study_resumes_from_its_run_folder(tmp_path, monkeypatch):
    import sys

    first = studies.faceting_study("quick", phantoms=["disk"], coatings=["aluminum"],
                                   run_dir=tmp_path)
    # the second run computes nothing: simulate must not be called
    def forbidden(*a, **k):
        raise AssertionError("a finished study point was computed again")

    monkeypatch.setattr(sys.modules["meshladar.forward"], "simulate", forbidden)
    monkeypatch.setattr(faceting, "simulate", forbidden)
    again = studies.faceting_study("quick", phantoms=["disk"], coatings=["aluminum"],
                                   run_dir=tmp_path)
    assert again["rows"] == first["rows"]
    np.testing.assert_array_equal(again["examples"]["disk/aluminum"]["mesh"],
                                  first["examples"]["disk/aluminum"]["mesh"])
    with pytest.raises(ml.runs.RunFolderError, match="different job"):
        studies.faceting_study("quick", phantoms=["disk"], coatings=["dark_gray"],
                               run_dir=tmp_path)


@pytest.mark.slow
def test_study_files(study, tmp_path):
    paths = studies.save_study(study, tmp_path)
    assert [p.split("/")[-1] for p in paths] == ["faceting.csv", "faceting.json",
                                                  "faceting_examples.npz"]
    doc = json.loads((tmp_path / "faceting.json").read_text())
    assert len(doc["rows"]) == len(study["rows"]) and doc["setting"] == "quick"
    lines = (tmp_path / "faceting.csv").read_text().splitlines()
    assert lines[0].startswith("phantom,coating,series") and len(lines) == len(study["rows"]) + 1
    assert "breaks at" in studies.report(study)
    from meshladar.viz import studies as vstudies
    import matplotlib.image as mpimg

    figs = vstudies.draw(tmp_path)
    names = sorted(p.split("/")[-1] for p in figs)
    assert names == ["difference_disk_aluminum.png", "difference_disk_diffuse_b0.99.png",
                     "error_vs_segments.png", "pareto.png"]
    for p in figs:
        assert mpimg.imread(p)[..., :3].std() > 0.02            # drawn, not blank
    from meshladar.viz import style

    @style.styled
    def no_crowding():
        for name, fig in vstudies.figures(tmp_path):
            assert style.overlapping_texts(fig) == [], name
    no_crowding()


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("big, small", [(DARK_GRAY, ALUMINUM), (ALUMINUM, DARK_GRAY)],
                         ids=["gray_al", "al_gray"])
@pytest.mark.parametrize("tol", [1e-2, pytest.param(1e-3, marks=pytest.mark.slow)])
def test_tol_knob_meets_the_accuracy_at_a_fair_cost(big, small, tol):
    scene = ml.phantoms.scene("disk_pair", large=big, small=small)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0))
    exact = ml.simulate(scene, ladar)
    got = ml.simulate(scene, ladar, model="mesh", tol=tol)
    assert _rel(got.values, exact.values) < tol
    chosen = got.info["chosen"]
    assert got.info["error_estimate"] <= tol and got.info["refinement"][-1]["rays_per_bin"] \
        == chosen["rays_per_bin"]
    # the cheapest point of a sweep (segments × rays per bin, same normals and binning) that
    # meets tol, by rays cast: the knob's choice costs at most 4× that (one doubling in each
    # direction, the price of checking by refinement)
    best = None
    for n in (256, 512, 1024, 2048):
        mesh = scene.tessellate(n)
        for r in (1, 2, 4, 8):
            s = ml.simulate(mesh, ladar, model="mesh", normals="exact", footprint=True,
                            rays_per_bin=r)
            if _rel(s.values, exact.values) < tol:
                best = s.info["rays"] if best is None else min(best, s.info["rays"])
                break
    assert best is not None and got.info["rays"] <= 4 * best


def test_tol_that_cannot_be_met_warns_and_reports(monkeypatch):
    # dark gray alone stalls near silhouettes (see the study): within two refinements its
    # estimate rises again (measured 0.0065 then 0.0095), so the knob stops there, warns,
    # and reports the best run it made, not the last
    from meshladar.forward import refine

    monkeypatch.setattr(refine, "_TOL_STEPS", 2)
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.5, DARK_GRAY)])
    lad = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0))
    with pytest.warns(ml.errors.MeshladarWarning, match=r"tol=1e-06 not reached: "
                                                        r"refinement stopped converging"):
        got = ml.simulate(scene, lad, model="mesh", tol=1e-6)
    runs = got.info["refinement"]
    best = min(runs[1:], key=lambda r: r["error_estimate"])
    assert runs[-1]["error_estimate"] > best["error_estimate"]
    assert got.info["chosen"]["rays_per_bin"] == best["rays_per_bin"] == 2.0
    assert got.info["chosen"]["segments"] == best["segments"] == 512
    assert got.info["error_estimate"] == best["error_estimate"] > 1e-6


def test_tol_validation():
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.5, DARK_GRAY)])
    lad = ml.Ladar.paper(angles_deg=[0.0])
    with pytest.raises(ml.errors.ParameterError, match=r"tol must be in \(0, 1\); got 0.0"):
        ml.simulate(scene, lad, model="mesh", tol=0.0)
    with pytest.raises(ml.errors.ParameterError, match="tol chooses the ray density"):
        ml.simulate(scene, lad, model="mesh", tol=0.01, rays_per_bin=4)


@pytest.mark.slow
def test_reconstruction_and_3d_study_figures(tmp_path):
    """The reconstruction and 3-D studies' figures (drawn by viz, not the CLI): one panel per
    method and spacing, or per volume; signed images on a scale symmetric about zero whose
    top is not below the image's 99.9th |value| percentile (the ring is not saturated);
    no text overlapping or cut off; the PNGs written."""
    import matplotlib.image as mpimg

    from meshladar.studies import reconstruction as study
    from meshladar.viz import studies as vstudies, style
    from meshladar.images import Volume

    rng = np.random.default_rng(1)
    x = np.linspace(-1, 1, 48)
    X, Y = np.meshgrid(x, x)
    ring = np.exp(-((np.hypot(X, Y) - 0.5) / 0.05) ** 2)
    images = {(ph, sp, m): 50 * ring + rng.normal(0, 1, ring.shape)
              for ph in ("b099_disk", "gray_al_pair") for sp in (1.0, 5.0, 10.0)
              for m in study.METHODS}
    del images[("gray_al_pair", 10.0, "compensated")]            # a method that failed
    vols = {k: Volume(np.stack([ring] * 4), x=x, y=x, z=np.arange(4.0))
            for k in ("lambertian", "b099", "glint", "pair_plain", "pair_log")}

    @style.styled
    def check():
        (name, fig), = vstudies.reconstruction_figures(images)
        assert name == "reconstruction.png"
        panels = [ax for ax in fig.axes if ax.images]
        assert len(panels) == 2 * 2 * len(study.METHODS) - 1
        for ax in panels:
            im = ax.images[0]
            data = np.asarray(im.get_array())
            assert im.norm.vmin == -im.norm.vmax
            assert im.norm.vmax >= np.percentile(np.abs(data), 99.9) * (1 - 1e-9)
        assert style.overlapping_texts(fig) == []
        (name, fig), = vstudies.tomography3d_figures(vols, 600, 48)
        assert name == "tomography3d.png" and sum(bool(a.images) for a in fig.axes) == 5
        assert style.overlapping_texts(fig) == []
    check()
    for path in (vstudies.draw_reconstruction(images, tmp_path)
                 + vstudies.draw_tomography3d(vols, tmp_path, 600, 48)):
        assert mpimg.imread(path)[..., :3].std() > 0.02
