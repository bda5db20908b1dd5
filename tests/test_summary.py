"""Results summarise themselves: a repr of a few hundred characters at most (shape, model,
range, units, conventions) whatever their size, and an HTML table in notebooks."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar import materials, paper
from meshladar._summary import MAX_REPR
from meshladar.ladar import Ladar


@pytest.fixture(scope="module")
def results():
    pair = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    lad = Ladar(np.arange(0.0, 360.0, 1.0), Ladar.centered(512, 1.6 / 512).bin_edges)
    sino = ml.simulate(pair, lad, radiometry="power")
    image = ml.Image(np.random.default_rng(0).random((1024, 1024)), 1.0,
                     info={"method": "sirt", "iterations": 50, "radiometry": "power"})
    hits = ml.trace(pair.tessellate(64), ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0)))
    from meshladar.fitting import coating_kernel, fit_coatings
    from meshladar.receiver import GaussianPulse, receive

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


def test_quick_looks(results, tmp_path):
    """Sinogram.plot() and Image.plot() return labelled Figures without pyplot state:
    units and radiometry on the colour bar, log input said so, no text overlapping or cut
    off, a colour scale symmetric about zero for the signed image."""
    from meshladar.viz import style

    sino = results["Sinogram"]
    fig = sino.plot(log=True)
    labels = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
    assert "radiometry power" in labels and "length/sr" in labels
    assert style.overlapping_texts(fig) == []
    img = ml.fbp(ml.log_radiance(sino), size=128)
    fig = img.plot()
    assert style.overlapping_texts(fig) == []
    im = fig.axes[0].images[0]
    assert im.norm.vmin == -im.norm.vmax
    labels = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
    assert "log input" in labels and "of log(floor=1e-06)" in labels
    fig.savefig(tmp_path / "quick.png")
    assert (tmp_path / "quick.png").stat().st_size > 5000
