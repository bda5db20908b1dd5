"""The paper's findings as numbers (Jin & Levine 2009, Figs 5-11), and its figures."""

from __future__ import annotations

import os

import numpy as np
import pytest

from meshladar import io as results
from meshladar.studies import paper


@pytest.fixture(scope="module")
def result():
    # the smallest size run() takes (475²: every finding within 0.1 + 5 % of its 512²
    # figure; 256² is refused, its ellipse figures moved by up to 0.28)
    return paper.run(size=paper.MIN_SIZE)


@pytest.mark.slow
def test_lambertian_disk_is_not_darkened(result):
    m = result["metrics"]
    # ≈ 0 (measured +0.06): a tenth of the b = 0.99 effect at most
    assert abs(m["disk_b0.darkening"]) < 0.1 * abs(m["disk_b0.99.darkening"])
    assert abs(m["disk_e1.darkening"]) < 0.1 * abs(m["disk_b0.99.darkening"])


@pytest.mark.slow
def test_glancing_loss_darkens_the_interior_boundary(result):
    m = result["metrics"]
    assert m["disk_b0.99.darkening"] < -0.8                       # measured −1.36
    # the glint's darkening is far deeper (measured 10×) and narrower (measured 6×)
    assert m["disk_e0.007.darkening"] < 5 * m["disk_b0.99.darkening"]
    assert m["disk_e0.007.darkening_width"] < 0.5 * m["disk_b0.99.darkening_width"]


@pytest.mark.slow
def test_ellipse_darkening_concentrates_at_the_tapered_ends(result):
    m = result["metrics"]
    assert m["ellipse_b0.99.ends_darkening"] < -1.5                     # measured −3.8
    assert m["ellipse_b0.99.ends_darkening"] < 3 * m["ellipse_b0.99.sides_darkening"]
    for k in ("ellipse_b0.ends_darkening", "ellipse_b0.sides_darkening"):
        assert abs(m[k]) < 0.1 * abs(m["ellipse_b0.99.ends_darkening"])


@pytest.mark.slow
def test_glints_hide_the_gray_disk_and_log_or_clip_recover_it(result):
    m = result["metrics"]
    for k in ("pair_gray_al.visibility", "pair_al_gray.visibility"):
        assert abs(m[k]) < 0.1                                     # measured 0.03, −0.003
    assert m["pair_gray_al_log.visibility"] > 0.5                  # measured 0.86
    assert m["pair_gray_al_clip.visibility"] > 0.5                 # measured 0.72


@pytest.mark.slow
def test_shadowing_leaves_range_gaps(result):
    # the pair's sinogram has empty bins between the disks' returns at views along x
    sino = result["sinograms"]["pair_gray_gray"]
    row = sino[0]
    lit = np.nonzero(row)[0]
    assert np.any(row[lit.min():lit.max()] == 0)


@pytest.mark.slow
def test_figures_are_drawn_from_the_saved_result(tmp_path):
    from meshladar.viz import paper as vpaper

    path, metrics = vpaper.save_run(tmp_path, size=paper.MIN_SIZE)    # 64 is refused
    arrays, meta = results.load_result(path)
    assert meta["metrics"] == metrics and meta["model"] == "analytic"
    assert arrays["image/disk_b0"].shape == (paper.MIN_SIZE, paper.MIN_SIZE)
    paths = vpaper.draw(path, tmp_path / "figs", dpi=40)
    assert [os.path.basename(p) for p in paths] == [f"fig{n:02d}.png" for n in range(5, 12)]
    import matplotlib.image as mpimg

    for p in paths:
        img = mpimg.imread(p)
        assert img.shape[0] > 100 and img.shape[1] > 200
        assert img[..., :3].std() > 0.05                       # not a blank canvas
    assert not list((tmp_path / "figs").glob("*.tmp*"))
    # picture content: no text overlaps another or leaves the figure; every image panel's
    # scale is symmetric (the rings' saturation is checked at the drawn size, 512², in
    # tests/viz/test_figure_scale.py)
    from meshladar.viz import style

    @style.styled
    def check():
        for n, fig in vpaper.figures(arrays, meta):
            assert style.overlapping_texts(fig) == [], n
            shown = [ax for ax in fig.axes if ax.images]
            assert len(shown) == (0 if n == 5 else 2), n
            for ax in shown:
                im = ax.images[0]
                assert im.norm.vmin == -im.norm.vmax              # symmetric about 0
    check()


@pytest.mark.slow
def test_received_power_darkens_even_a_lambertian_ellipse(result):
    """The question the paper did not ask: with received power as the data (one cos θ more),
    the Lambertian disk's surface band stays level (every boundary point sees the same
    incidences), but the Lambertian ellipse's tapered ends darken (measured −0.64 at 256²,
    −0.82 at 512², against +0.02 and −0.12 with Eq. 8), and glossy coatings darken more
    (disk b = 0.99: −2.02 against −1.36)."""
    m = result["metrics"]
    assert abs(m["power.disk_b0.darkening"]) < 0.1 * abs(m["disk_b0.99.darkening"])
    assert m["power.ellipse_b0.ends_darkening"] < -0.3
    assert m["power.ellipse_b0.ends_darkening"] < m["ellipse_b0.ends_darkening"] - 0.3
    assert m["power.ellipse_b0.ends_darkening"] < 2 * m["power.ellipse_b0.sides_darkening"]
    assert m["power.disk_b0.99.darkening"] < 1.3 * m["disk_b0.99.darkening"]
    assert m["power.ellipse_b0.99.ends_darkening"] < m["ellipse_b0.99.ends_darkening"]
    # glints still hide the gray disk; log and clip still recover it
    assert abs(m["power.pair_gray_al.visibility"]) < 0.1
    assert m["power.pair_gray_al_log.visibility"] > 0.5
    assert m["power.pair_gray_al_clip.visibility"] > 0.5


@pytest.fixture(scope="module")
def result_3d():
    # the quick setting of `meshladar study tomography3d` (~12 s)
    return paper.run_3d(views=600, size=64, smooth=1.0, rays_per_bin=1.0)[0]


@pytest.mark.slow
def test_the_findings_hold_in_3d(result_3d):
    """The paper's findings, measured in 3-D (spheres seen from 600 directions over the
    sphere, 64³): glancing loss darkens the b = 0.99 sphere's inner shell well below the
    Lambertian's (measured −0.92 against +2.07; −4.97 against +0.90 at 2000 views and
    128³), the glint's far more (−19.4); the aluminium sphere's glint hides the gray one,
    and log or clip input raises it (visibility 0.34 → 0.67, 1.55); mutual shadowing adds
    streaks (their RMS outside the spheres, 3.8 × the gray shell's peak)."""
    m = result_3d
    assert m["3d.sphere_b0.99.darkening"] < m["3d.sphere_b0.darkening"] - 1.5
    assert m["3d.sphere_e0.007.darkening"] < m["3d.sphere_b0.99.darkening"] - 10
    assert m["3d.pair_gray_al_log.visibility"] > 1.5 * m["3d.pair_gray_al.visibility"]
    assert m["3d.pair_gray_al_clip.visibility"] > 1.5 * m["3d.pair_gray_al.visibility"]
    assert m["3d.pair.shadow_streaks"] > 0.3


def test_the_panels_are_built_from_the_phantom_specs():
    """Every figure's panels exist, and the lone disk, the ellipse and the pair are the
    phantom library's (radius A = 0.8; semi-axes 0.6 × 0.3; the touching pair)."""
    panels = paper._panels()
    assert {k for _, keys in paper.FIGURES.values() for k in keys} <= set(panels)
    disk = panels["disk_b0"][0].shapes[0]
    assert disk.radius == 0.8 and tuple(disk.center) == (0.0, 0.0)
    assert tuple(panels["ellipse_b0"][0].shapes[0].axes) == (0.6, 0.3)
    assert [s.name for s in panels["pair_gray_al"][0].shapes] == ["large", "small"]
