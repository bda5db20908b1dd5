"""Results summarise themselves: a repr of a few hundred characters at most (shape, model,
range, units, conventions) whatever their size, and an HTML table in notebooks."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar import materials
from meshladar.studies import paper
from meshladar._summary import MAX_REPR
from meshladar.ladar import Ladar
from meshladar.errors import ParameterError


@pytest.fixture(scope="module")
def results():
    pair = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    lad = Ladar(np.arange(0.0, 360.0, 1.0), Ladar.centered(512, 1.6 / 512).bin_edges)
    sino = ml.simulate(pair, lad, radiometry="power")
    image = ml.Image(np.random.default_rng(0).random((1024, 1024)), 1.0,
                     info={"method": "sirt", "iterations": 50, "radiometry": "power"})
    hits = ml.trace(pair.tessellate(64), ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0)))
    from meshladar.fit import coating_kernel, fit_coatings
    from meshladar.waveforms import GaussianPulse, receive

    kernel = coating_kernel(pair, Ladar(lad.angles_deg[::10], lad.bin_edges), samples=512)
    fit = fit_coatings(kernel, kernel.sinogram(), parts=["small"], free=("rho_d",))
    waves = receive(sino, sample_rate=20e9, pulse=GaussianPulse(1e-10))
    return {"Sinogram": sino, "Image": image, "Hits": hits, "Waveforms": waves,
            "CoatingKernel": kernel, "CoatingFit": fit}


@pytest.mark.parametrize("name", ["Sinogram", "Image", "Hits", "Waveforms", "CoatingKernel",
                                  "CoatingFit"])
def test_reprs_summarise(results, name):
    obj = results[name]
    text = repr(obj)
    assert text.startswith(name + "(") and len(text) <= MAX_REPR
    assert "array(" not in text and "\n" not in text
    html = obj._repr_html_()
    assert html.startswith("<table>") and name in html


def test_reprs_state_conventions(results):
    assert "radiometry='power'" in repr(results["Sinogram"])
    assert "units=" in repr(results["Sinogram"])
    assert "method='sirt'" in repr(results["Image"]) and "iterations=50" in repr(results["Image"])
    assert "mode='slice'" in repr(results["Hits"]) and "normals='flat'" in repr(results["Hits"])
    assert "small.rho_d=" in repr(results["CoatingFit"])
    log = ml.fbp(ml.log_radiance(results["Sinogram"]), size=64)
    assert "input='log(floor=1e-06)'" in repr(log)
    assert "input_units='dimensionless" in repr(log)              # log input has no unit
    assert "input_units='area/sr'" in repr(ml.fbp(results["Sinogram"], size=64)) or \
        "input_units='length/sr" in repr(ml.fbp(results["Sinogram"], size=64))
    assert "views='about z, w = (cos φ, sin φ, 0)'" in repr(results["Sinogram"])
    assert " ns (two-way)'" in repr(results["Waveforms"])
    html = results["Sinogram"]._repr_html_()
    assert "<td style='text-align:left'>analytic</td>" in html   # strings without quotes


@pytest.mark.slow
def test_quick_looks(results, tmp_path):
    """Sinogram.plot() and Image.plot() return labelled Figures without pyplot state:
    units and radiometry on the colour bar, log input said so, no text overlapping or cut
    off, a colour scale symmetric about zero for the signed image."""
    from meshladar.viz import style

    sino = results["Sinogram"]
    fig = sino.plot(log=True)
    labels = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
    assert "power radiometry" in labels and "length/sr" in labels
    assert "view angle φ [deg]" in labels and "[scene units]" in labels
    assert style.overlapping_texts(fig) == []
    assert fig.dpi == 150                        # a user's fig.savefig is at 150 dpi too
    # by default the scale is logarithmic when the values span more than three decades
    # (the glint next to the gray disk), with empty bins in the lowest colour, not white
    im = sino.plot().axes[0].images[0]
    assert im.norm.__class__.__name__ == "LogNorm"
    assert tuple(im.cmap.get_bad()[:3]) == tuple(im.cmap(0.0)[:3])
    flat = ml.Sinogram(np.ones((3, 4)), angles_deg=[0, 10, 20], bin_edges=np.arange(5.0))
    assert flat.plot().axes[0].images[0].norm.__class__.__name__ == "Normalize"
    img = ml.fbp(ml.log_radiance(sino), size=128)
    fig = img.plot()
    assert style.overlapping_texts(fig) == []
    im = fig.axes[0].images[0]
    assert im.norm.vmin == -im.norm.vmax
    labels = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
    assert "log input" in labels and "of log(floor=1e-06)" in labels
    slice_axes = fig.axes[1]                      # the image, then the slice (then the bar)
    assert slice_axes.get_title() == "slice"
    assert "[scene units]" in slice_axes.get_xlabel()
    assert slice_axes.get_ylabel() == "value of log input"        # units on both axes
    fig.savefig(tmp_path / "quick.png")
    assert (tmp_path / "quick.png").stat().st_size > 5000


def test_profile_against_a_closed_form_and_waveform_quick_look():
    """The analytic check as a picture: the Lambertian disk's profile against its closed
    form (Eq. 8: ρ/π ∫ cos² over the arc, per bin; identical to rounding), and the
    waveforms' quick look with a noise band."""
    from meshladar.brdf import Lambertian
    from meshladar.noise import Noise
    from meshladar.scene import Scene
    from meshladar.shapes import Disk
    from meshladar.viz import quick, style

    R = 0.5
    lad = Ladar([90.0], Ladar.centered(64, 1.2 / 64).bin_edges)
    sino = ml.simulate(Scene([Disk((0.0, 0.0), R, Lambertian(1.0))]), lad)

    def closed(edges):
        # a point at range r = −R cos θ has weight (1/π) cos θ per length R dθ, two sides:
        # ∫ (2R/π) cos θ dθ from the bin's θ-interval = (2R/π) Δ sin θ
        c = np.clip(-edges / R, 0.0, 1.0)
        s = np.sqrt(1.0 - c * c)
        return (2 * R / np.pi) * np.abs(np.diff(s))

    np.testing.assert_allclose(sino.values[0], closed(lad.bin_edges), rtol=0, atol=1e-12)
    fig = quick.profile(sino, closed, label="closed form")
    assert style.overlapping_texts(fig) == []
    assert "relative L2 difference" in fig.axes[1].get_title()
    # a sinogram on the same bins is a reference too (its same view); others are refused
    mesh = ml.simulate(Scene([Disk((0.0, 0.0), R, Lambertian(1.0))]), lad, model="mesh",
                       mode="slice", ray_spacing=1e-3)
    fig = quick.profile(mesh, sino, label="analytic")
    drawn = fig.axes[0].patches[1].get_data().values
    np.testing.assert_array_equal(drawn, sino.values[0])
    other = ml.simulate(Scene([Disk((0.0, 0.0), R, Lambertian(1.0))]),
                        Ladar([90.0], Ladar.centered(32, 1.2 / 32).bin_edges))
    with pytest.raises(ParameterError, match="other bin edges"):
        quick.profile(sino, other)
    with pytest.raises(ParameterError, match="must be a Sinogram"):
        quick.profile(sino, "closed form")
    waves = results_waves()
    fig = waves.plot(noise=Noise(), realisations=4)
    assert style.overlapping_texts(fig) == []
    assert any(c.__class__.__name__ == "FillBetweenPolyCollection" or
               c.__class__.__name__ == "PolyCollection" for c in fig.axes[0].collections)
    # 1e8 photoelectrons: engineering labels ("50 M"), no "1e8" offset text for the top
    # axis's labels to cover
    big = results_waves(peak=1e8)
    fig = big.plot(noise=Noise(), realisations=4)
    assert style.overlapping_texts(fig) == []
    for ax in fig.axes:
        if ax.get_ylabel():
            assert ax.yaxis.get_offset_text().get_text() == ""
            assert any(t.get_text().endswith(" M") for t in ax.get_yticklabels())
    # a digitiser that clips every sample with signal: the band sits on its full scale,
    # drawn and labelled with the view's clipped fraction
    clip = Noise(bits=8, full_scale=1e3)
    with pytest.warns(ml.errors.MeshladarWarning, match=r"[\d.]+ % of the noisy samples clip"):
        fig = big.plot(noise=clip, realisations=4)
    labels = [t for t in fig.axes[0].get_legend_handles_labels()[1] if "full scale" in t]
    assert len(labels) == 1 and labels[0].endswith("% clipped"), labels
    assert style.overlapping_texts(fig) == []


def results_waves(peak=1e4):
    from meshladar.waveforms import GaussianPulse, receive

    pair = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    lad = Ladar(np.arange(0.0, 360.0, 30.0), Ladar.centered(128, 1.6 / 128).bin_edges)
    sino = ml.simulate(pair, lad, radiometry="power")
    w = receive(sino, sample_rate=20e9, pulse=GaussianPulse(1e-10))
    return w.scaled(peak / w.values.max(), units="photoelectrons")


def test_inputs_summarise_too():
    """Scene, Ladar and MeshPart summarise (kind, parts, faces, coatings, bounds; views and
    bins) instead of dumping vertex arrays: a 1.3M-face mesh's repr is as short as a disk's,
    and a scene of 40 shapes lists a few and counts the rest."""
    big = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=6)],
                              materials=[materials.ALUMINUM])
    text = repr(big)
    assert len(text) <= MAX_REPR and "array(" not in text
    assert "kind='mesh'" in text and "faces=81920" in text and "materials='aluminum'" in text
    assert "parts='sphere: 81920 faces'" in text        # a part's name, then its faces
    assert "bounds='[-0.5, -0.5, -0.5] to [0.5, 0.5, 0.5]'" in text and "watertight=True" in text
    part = repr(big.parts[0])
    assert part.startswith("MeshPart(name='sphere'") and "faces=81920" in part
    assert len(part) <= MAX_REPR
    many = ml.Scene([ml.Disk((0.1 * k, 0.0), 0.04, materials.DARK_GRAY, name=f"d{k}")
                     for k in range(40)])
    text = repr(many)
    assert "kind='analytic'" in text and "(+36 more)" in text and len(text) <= MAX_REPR
    assert "<table>" in many._repr_html_() and "Scene" in many._repr_html_()
    lad = repr(Ladar.paper())
    assert lad == ("Ladar(n_views=360, n_bins=512, range=(-0.8, 0.8), bin_width=0.003125, "
                   "views='about z, 0 to 359 deg every 1')")
    sphere = Ladar(None, np.linspace(-1, 1, 5), view_vectors=ml.meshes.fibonacci_sphere(10))
    assert "views='3-D directions'" in repr(sphere) and "<table>" in sphere._repr_html_()
    uneven = Ladar([0.0, 10.0, 30.0], [0.0, 1.0, 3.0])
    assert "bin_width='uneven'" in repr(uneven) and "every" not in repr(uneven)
