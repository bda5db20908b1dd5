"""The phantom library: the paper's phantoms as declarative specs."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar import phantoms
from meshladar.errors import PhantomSpecError
from meshladar.materials import ALUMINUM, DARK_GRAY


def test_packaged_phantoms_are_the_papers():
    assert phantoms.names() == ["disk", "disk_pair", "ellipse"]
    disk = phantoms.load("disk")
    (d,) = disk.scene.shapes
    assert d.radius == 0.8 and d.center == (0.0, 0.0)
    ell = phantoms.load("ellipse").scene.shapes[0]
    assert ell.semi_axes == (0.6, 0.3)
    big, small = phantoms.load("disk_pair").scene.shapes
    assert (big.radius, small.radius) == (0.4, 0.3)
    # adjacent: touching, not overlapping
    assert np.hypot(big.center[0] - small.center[0], big.center[1] - small.center[1]) == \
        pytest.approx(0.7, rel=1e-15)
    # the paper's set-up: A/256 bins (A = 0.8), 360 views at 1°
    lad = disk.ladar
    assert lad.n_views == 360 and lad.n_bins == 512
    np.testing.assert_allclose(np.diff(lad.bin_edges), 0.8 / 256)


@pytest.mark.parametrize("large, small", [("dark_gray", "aluminum"), ("aluminum", "dark_gray"),
                                          (ALUMINUM, ALUMINUM)])
def test_either_coating_on_either_disk(large, small):
    p = phantoms.load("disk_pair", materials={"large": large, "small": small})
    big, sm = p.scene.shapes
    want = {"dark_gray": DARK_GRAY, "aluminum": ALUMINUM}
    assert big.material == want.get(large, large) and sm.material == want.get(small, small)


def test_inline_material_override():
    p = phantoms.load("disk", materials={"disk": {"rho_d": 0.5, "epsilon": 0.0, "b": 0.0,
                                                  "e": 1.0, "lobes": "diffuse"}})
    assert p.scene.shapes[0].material == ml.materials.lambertian(0.5)


def test_spec_errors(tmp_path):
    with pytest.raises(PhantomSpecError, match=r"unknown phantom; packaged phantoms are"):
        phantoms.load("dsik")
    with pytest.raises(PhantomSpecError, match=r"materials: no shape named 'huge'"):
        phantoms.load("disk_pair", materials={"huge": "aluminum"})
    with pytest.raises(PhantomSpecError, match=r"unknown material 'gold'"):
        phantoms.load("disk_pair", materials={"large": "gold"})
    bad = tmp_path / "bad.toml"
    bad.write_text('[[shape]]\nkind = "disk"\ncenter = [0, 0]\nradius = -1\n'
                   'material = "aluminum"\n')
    with pytest.raises(PhantomSpecError, match=r"bad.toml: \[\[shape\]\] 0 .*radius must be"):
        phantoms.load(bad)
    bad.write_text('[[shape]]\nkind = "square"\n')
    with pytest.raises(PhantomSpecError, match=r"kind must be one of \('disk', 'ellipse'\)"):
        phantoms.load(bad)
    bad.write_text('[[shape]]\nkind = "disk"\ncenter = [0, 0]\nradius = 1\nmaterial = "aluminum"'
                   '\ncolour = 3\n')
    with pytest.raises(PhantomSpecError, match=r"unknown field 'colour' for a disk"):
        phantoms.load(bad)
    bad.write_text('[[shape]]\nkind = "disk"\ncenter = [0, 0]\nradius = 0.5\nmaterial = "aluminum"'
                   '\n[[shape]]\nkind = "disk"\ncenter = [0.5, 0]\nradius = 0.5\n'
                   'material = "aluminum"\n')
    with pytest.raises(PhantomSpecError, match=r"overlap"):
        phantoms.load(bad)
    with pytest.raises(PhantomSpecError, match=r"cannot read phantom spec"):
        phantoms.load(tmp_path / "missing.toml")


def test_spec_from_file_simulates(tmp_path):
    spec = tmp_path / "mine.toml"
    spec.write_text('name = "mine"\n[ladar]\nbin_edges = [-1.0, 0.0, 1.0]\nangles_deg = [0.0, 90.0]'
                    '\n[[shape]]\nkind = "ellipse"\ncenter = [0, 0]\nsemi_axes = [0.5, 0.25]\n'
                    'angle_deg = 30\nmaterial = "lambertian"\n')
    p = phantoms.load(spec)
    sino = ml.simulate(p.scene, p.ladar)
    # Lambertian ρd = 1: the total is the projected width (support-function width) / π
    a, b, t = 0.5, 0.25, np.deg2rad(30.0)
    for i, phi in enumerate(np.deg2rad([0.0, 90.0])):
        beta = phi - t
        width = 2 * np.hypot(a * np.sin(beta), b * np.cos(beta))
        assert sino.total()[i] == pytest.approx(width / np.pi, rel=1e-12)


def test_the_old_source_loader_name_warns_and_still_loads():
    # phantoms.resolve became the command line's source loader; the old name works for a
    # release, warning with the new one's name
    from meshladar.cli.sources import load_source

    with pytest.warns(DeprecationWarning, match="load_source"):
        old = ml.phantoms.resolve
    assert old is load_source
    scene, ladar, model = old("disk_pair")
    assert model == "analytic" and ladar.n_views == 360 and len(scene.shapes) == 2
