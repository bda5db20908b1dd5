"""`meshladar reconstruct` frames its image as the API does: no --extent gives the same grid
as ``meshladar.fbp(sino)`` and ``fbp3d(sino)``, the bins' reach about the origin."""

from __future__ import annotations

import math
import re
import sys
import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar import cli, io
from meshladar.brdf import Lambertian
from meshladar.images import Volume
from meshladar.meshes import fibonacci_sphere
from meshladar.reconstruct.volumes import fbp3d

pytest.importorskip("matplotlib")


def _reconstruct(tmp_path, sino, size):
    from meshladar.cli import main

    path = tmp_path / "s.npz"
    ml.io.save_sinogram(path, sino)
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "s.png"), "--size",
                 str(size), "--quiet"]) == 0
    return tmp_path / "s"


def test_the_command_lines_image_is_the_apis_default_image(tmp_path):
    """A disk of radius 50 (mm) at (30, −20): the command's image and ``ml.fbp(sino)`` are
    one image on one grid, half-width |C| + R (the bins' reach), the disk inside it."""
    scene = ml.Scene([ml.Disk((30.0, -20.0), 50.0, ml.materials.lambertian(0.5))])
    sino = ml.simulate(scene, ml.Ladar.covering(scene, n_bins=128))
    stem = _reconstruct(tmp_path, sino, 64)
    arrays, meta = ml.io.load_result(str(stem) + ".image.npz")
    api = ml.fbp(sino, size=64)
    assert meta["extent"] == api.extent == pytest.approx(math.hypot(30.0, -20.0) + 50.0)
    np.testing.assert_allclose(arrays["image"], api.values, rtol=0,
                               atol=1e-12 * np.abs(api.values).max())


def test_the_command_lines_volume_is_the_apis_default_volume(tmp_path):
    """Views over the sphere: the command's volume is ``fbp3d(sino)``'s, voxel for voxel (it
    had 15 % more room than the API's cube)."""
    W = fibonacci_sphere(300)
    edges = np.linspace(-60.0, 60.0, 49)
    a = 40.0
    lo, hi = np.clip(edges[:-1], -a, a), np.clip(edges[1:], -a, a)
    vals = np.broadcast_to(math.pi * (a * a * (hi - lo) - (hi ** 3 - lo ** 3) / 3), (300, 48))
    sino = ml.Sinogram(vals, angles_deg=np.degrees(np.arctan2(W[:, 1], W[:, 0])),
                       bin_edges=edges, view_vectors=W)
    stem = _reconstruct(tmp_path, sino, 24)
    arrays, meta = ml.io.load_result(str(stem) + ".volume.npz")
    api = fbp3d(sino, size=24)
    cli = Volume(arrays["values"], x=arrays["x"], y=arrays["y"], z=arrays["z"])
    assert meta["info"]["extent"] == api.info["extent"] == 60.0
    for axis in "xyz":
        np.testing.assert_array_equal(getattr(cli, axis), getattr(api, axis))
    # the same sums, in an order the saved copy's memory layout may change: rounding apart
    np.testing.assert_allclose(cli.values, api.values, rtol=0,
                               atol=1e-12 * np.abs(api.values).max())


def test_a_volume_that_would_overwrite_its_input_is_refused_before_the_work(
        tmp_path, monkeypatch, capsys):
    # -o a.png writes a.volume.npz beside it: an input of that name is refused, untouched,
    # before the inversion runs (it is not there to run)
    from meshladar.cli import main, reconstruct

    W = fibonacci_sphere(50)
    # the angles agree with the vectors' azimuths (a Sinogram refuses a contradiction)
    sino = ml.Sinogram(np.ones((50, 8)), angles_deg=np.degrees(np.arctan2(W[:, 1], W[:, 0])),
                       bin_edges=np.linspace(-1.0, 1.0, 9), view_vectors=W)
    path = tmp_path / "a.volume.npz"
    ml.io.save_sinogram(path, sino)
    before = path.read_bytes()
    monkeypatch.setattr(reconstruct, "fbp3d", None)
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "a.png"), "--quiet"]) == 2
    assert "would write the volume" in capsys.readouterr().err
    assert path.read_bytes() == before


def test_a_target_far_from_the_axis_is_framed_by_the_flags_the_warning_names(tmp_path,
                                                                              capsys):
    """A user's trial: a target 1e4 units from the axis reconstructed into streaks in the
    default square with no word. The warning names --center X,Y and --extent E (the
    API's center=(X, Y) in the flags' words), and those flags frame the disk: its rim
    within 0.1 of its radius from its centre (30, -20), placed by hand."""
    scene = ml.Scene([ml.Disk((30.0, -20.0), 1.0, Lambertian(0.5))])
    ladar = ml.Ladar(np.arange(180) * 2.0, np.linspace(-40.0, 40.0, 2049))
    io.save_sinogram(tmp_path / "far.npz", ml.simulate(scene, ladar))
    out = str(tmp_path / "far.image.npz")
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda m, c, f, n, file=None, line=None: sys.stderr.write(
            warnings.formatwarning(m, c, f, n))
        assert cli.main(["reconstruct", str(tmp_path / "far.npz"), "-o", out,
                         "--size", "64"]) == 0
    err = capsys.readouterr().err
    found = re.search(r"--center ([-\d.]+),([-\d.]+) and --extent ([\d.]+) frame it", err)
    assert found, err
    assert cli.main(["reconstruct", str(tmp_path / "far.npz"), "-o", out, "--size", "256",
                     "--center", f"{found[1]},{found[2]}", "--extent", found[3]]) == 0
    data = np.load(out)
    values, extent = data["image"], float(found[3])
    i, j = np.unravel_index(np.argmax(values), values.shape)
    x = float(found[1]) - extent + (j + 0.5) * 2 * extent / 256
    y = float(found[2]) - extent + (i + 0.5) * 2 * extent / 256
    assert abs(np.hypot(x - 30.0, y + 20.0) - 1.0) < 0.1
