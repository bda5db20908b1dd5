"""The pyvista viewer, rendered off screen for real; the pictures' content is checked."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.ndimage import center_of_mass, label

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY, lambertian

from _rendering import _SMOKE, slot_left  # noqa: E402  (tests/, on the path with the conftest)


@pytest.fixture(scope="module", autouse=True)
def rendering():
    # VTK segfaults instead of raising when off-screen rendering is missing: probe in a
    # subprocess and turn a crash into a clear message
    res = subprocess.run([sys.executable, "-c", _SMOKE], capture_output=True, text=True,
                         timeout=300)
    if res.returncode != 0:
        msg = ("off-screen rendering does not work here (exit code "
               f"{res.returncode}): install Debian's libegl1 and libgl1-mesa-dri "
               "(.ci/run does)\n" + res.stderr[-2000:])
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)


def _is(img, color, tol=0.08):
    return np.all(np.abs(img[..., :3] / 255.0 - np.asarray(color)) < tol, axis=-1)


def test_shadowed_part_of_the_disk_pair_is_drawn_in_the_shadow_colour():
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
    # from +x the small disk hides the large one's middle: a band of shadow colour
    img = viewer.show_scene(pair, view_angle_deg=0.0, show_rays=False, off_screen=True,
                            window_size=(400, 300)).image
    shadow = _is(img, viewer.SHADOW_COLOR)
    assert shadow.sum() > 1000
    # from +y nothing is shadowed
    img = viewer.show_scene(pair, view_angle_deg=90.0, show_rays=False, off_screen=True,
                            window_size=(400, 300)).image
    assert _is(img, viewer.SHADOW_COLOR).sum() == 0
    # the headless EGL window is chosen for the call only: the environment is left as it was
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        assert "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ


def test_lit_lambertian_sphere_is_brightest_at_its_centre(tmp_path):
    from meshladar.viz import viewer

    sphere = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=4)],
                                 [lambertian(1.0)])
    shot = tmp_path / "sphere.png"
    shown = viewer.show_scene(sphere, view_vector=[0, 0, 1], show_rays=False,
                              off_screen=True, screenshot=shot, window_size=(300, 300),
                              camera="view")
    assert shot.is_file()
    img = shown.image
    (_, (x0, _, _, _)), = shown.scalar_bars
    gray = img[..., :3].astype(float).sum(axis=-1)[:, :int(x0 * 300) - 2]  # left of the bar
    _, ly0, lx1, _ = shown.legend.box                # the legend, top left (y up)
    disc = gray > 0
    disc[:int(np.ceil((1 - ly0) * 300)) + 2, :int(np.ceil(lx1 * 300)) + 2] = False
    # the sphere's disc: its rows, then along its middle row the run of lit pixels from
    # its left edge (the bar's title, beyond a black gap, is not the sphere)
    rows = np.nonzero(disc.any(axis=1))[0]
    ci = 0.5 * (rows.min() + rows.max())
    line = disc[int(round(ci))]
    left = int(np.argmax(line))
    right = left + int(np.argmin(line[left:])) - 1
    cj, radius = 0.5 * (left + right), 0.5 * (rows.max() - rows.min())
    assert radius > 40 and abs(radius - 0.5 * (right - left)) < 3
    gray = gray[:, :right + 1]
    # F cos θ = cos θ/π peaks where the normal faces the ladar: the sphere's centre (the
    # brightest facets, within 2% of the maximum, gather around it: their centroid)
    ii, jj = np.nonzero(gray >= 0.98 * gray.max())
    assert abs(ii.mean() - ci) < 0.1 * radius and abs(jj.mean() - cj) < 0.1 * radius
    # and falls off toward the limb
    i, j = int(round(ci)), int(round(cj))
    assert gray[i, j] > gray[i, j + int(0.6 * radius)] > gray[i, j + int(0.9 * radius)]


def test_slice_sits_at_its_position():
    """Cell (i, j) sits at (x_j, y_i): x to the right, y up, each at its distance from the
    centre. The picture is framed clear of the bar, so positions are read against each
    other: a bright cell at (x, y) ≈ (+0.58, +0.3), a dimmer one at (−0.58, +0.3), a dim
    one at (0, +0.86) (above the rows where the bar's title is found)."""
    from meshladar.viz import viewer

    values = np.zeros((64, 64))
    values[41, 50], values[41, 13], values[59, 32] = 0.8, 0.5, 0.25
    image = ml.Image(values, 1.0)
    shown = viewer.show_slice(image, z=0.3, clim=(0.0, 1.0), off_screen=True,
                              window_size=(600, 300))
    left = shown.image[:, :slot_left(shown) - 2, :3].astype(float).mean(axis=-1)  # picture

    spots, n = label(left > 15)
    assert n == 3
    found = sorted((left[spots == k].max(), *center_of_mass(spots == k))
                   for k in range(1, 4))                   # dimmest first
    (_, i_u, j_u), (_, i_l, j_l), (_, i_r, j_r) = found
    cell = (j_r - j_l) / 37                                # pixels per cell
    assert cell > 2 and abs(i_r - i_l) < 1.0               # x to the right, same row
    assert abs(j_u - j_l - 19 * cell) < 1.0                # at x's cell 32
    assert abs(i_r - i_u - 18 * cell) < 1.0                # y up, x's scale


def test_volume_iso_surface_of_a_stack():
    from meshladar.viz import viewer

    x = np.linspace(-1, 1, 32)
    X, Y = np.meshgrid(x, x)
    zs = np.linspace(-0.5, 0.5, 8)
    images = [ml.Image((np.hypot(X, Y) < 0.5).astype(float), 1.0) for _ in zs]
    img = viewer.show_volume(images, zs, iso=0.5, off_screen=True,
                             window_size=(200, 200)).image
    assert (img[..., :3].sum(axis=-1) > 100).sum() > 500      # a cylinder was drawn
    with pytest.raises(ValueError, match="evenly spaced"):
        viewer.show_volume(images, np.r_[zs[:-1], 9.0], iso=0.5, off_screen=True)


@pytest.mark.slow
def test_show_volume_of_a_reconstructed_ball():
    """A Volume (3-D Radon inversion of a uniform ball) draws as its default iso-surface."""
    from meshladar.meshes import fibonacci_sphere
    from meshladar.viz import viewer
    from meshladar.reconstruct.volumes import fbp3d as radon3d

    a, W = 0.5, fibonacci_sphere(200)
    edges = np.linspace(-1.0, 1.0, 49)
    lo, hi = np.clip(edges[:-1], -a, a), np.clip(edges[1:], -a, a)
    vals = np.broadcast_to(np.pi * (a * a * (hi - lo) - (hi ** 3 - lo ** 3) / 3), (200, 48))
    sino = ml.Sinogram(vals, bin_edges=edges, view_vectors=W)
    vol = radon3d(sino, size=32, extent=1.0)
    surf = viewer.volume_surface(vol)
    r = np.linalg.norm(np.asarray(surf.points), axis=1)
    assert abs(np.median(r) - a) < 2.0 / 32                  # the ball's sphere
    img = viewer.show_volume(vol, off_screen=True, window_size=(200, 200)).image
    assert (img[..., :3].sum(axis=-1) > 100).sum() > 500
    with pytest.raises(ValueError, match="zs"):
        viewer.show_volume(vol, [0.0, 1.0], off_screen=True)


def test_colour_bars_are_titled_and_apart():
    """With a ladar the scene shows two quantities, the return and the hits' range bin:
    two titled colour bars that do not overlap; a slice's bar says what it shows."""
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair")
    ladar = ml.Ladar.paper(angles_deg=[90.0])
    shown = viewer.show_scene(pair, ladar=ladar, off_screen=True, window_size=(300, 240))
    bars = list(shown.scalar_bars)
    assert sorted(t for t, _ in bars) == ["F cos(theta) [1/sr]", "first hits: range bin"]
    (_, a), (_, b) = bars
    assert a[3] <= b[1] or b[3] <= a[1] or a[2] <= b[0] or b[2] <= a[0]      # apart
    sino = ml.simulate(pair, ml.Ladar(np.arange(0.0, 360.0, 1.0),
                                      ml.Ladar.centered(64, 1.6 / 64).bin_edges))
    shown = viewer.show_slice(ml.fbp(ml.log_radiance(sino), size=64), off_screen=True,
                              window_size=(200, 200))
    assert [t for t, _ in shown.scalar_bars] == ["reconstruction of log input"]


def test_legend_names_the_flat_colours_clear_of_the_bars_and_text_is_legible():
    """The flat colours (shadowed, turned away, beam, iso-range planes) are named in a
    legend that overlaps no colour bar; the bars' titles and labels are drawn light on the
    black background (they were black on black: present in VTK, invisible on screen)."""
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
    w, h = 600, 480
    shown = viewer.show_scene(pair, view_angle_deg=0.0, ladar=ml.Ladar.paper(),
                              off_screen=True, window_size=(w, h))
    img = shown.image
    labels, box = shown.legend.labels, shown.legend.box
    assert list(labels) == ["shadowed (another face in the way)", "turned away from the ladar",
                      "ladar beam and ray grid", "iso-range planes (bin edges)"]
    for _, bar in shown.scalar_bars:
        assert box[2] <= bar[0] or bar[2] <= box[0] or box[3] <= bar[1] or bar[3] <= box[1]
    # light text right of each bar (its labels) and above it (its title)
    for _, (x0, y0, x1, y1) in shown.scalar_bars:
        labels_px = img[int((1 - y1) * h):int((1 - y0) * h), int(x1 * w):, :3]
        title_px = img[max(0, int((1 - y1) * h) - 30):int((1 - y1) * h),
                       int((x0 - 0.1) * w):, :3]
        assert (labels_px.min(axis=-1) > 150).sum() > 20
        assert (title_px.min(axis=-1) > 150).sum() > 20
    # the legend's text is white whatever its swatch (the dark blue was unreadable)
    x0, y0, x1, y1 = box
    legend_px = img[int((1 - y1) * h):int((1 - y0) * h), int(x0 * w):int(x1 * w), :3]
    assert (legend_px.min(axis=-1) > 200).sum() > 200
    # no ladar, no rays: nothing flat to name but the shadows and the far sides
    quiet = viewer.show_scene(pair, view_angle_deg=90.0, show_rays=False, off_screen=True,
                              window_size=(200, 160))
    assert list(quiet.legend.labels) == ["turned away from the ladar"]
    # np.asarray of what was shown is its image (ax.imshow(shown) keeps working)
    assert np.asarray(quiet).shape == (160, 200, 3)
    with pytest.raises(ml.errors.ParameterError, match="camera"):
        viewer.show_scene(pair, camera="top", off_screen=True)


def test_volume_default_is_a_surface_not_fog():
    """A stack of disks drawn by default: the iso-surface at half the robust peak (a solid
    cylinder whose pixels are bright), not a grey fog; render='volume' is a windowed
    volume rendering."""
    from meshladar.viz import viewer

    x = np.linspace(-1, 1, 32)
    X, Y = np.meshgrid(x, x)
    zs = np.linspace(-0.5, 0.5, 8)
    images = [ml.Image(3.0 * (np.hypot(X, Y) < 0.5), 1.0) for _ in zs]
    img = viewer.show_volume(images, zs, off_screen=True, window_size=(200, 200)).image
    assert (img[..., :3].sum(axis=-1) > 300).sum() > 500
    img = viewer.show_volume(images, zs, render="volume", off_screen=True,
                             window_size=(200, 200)).image
    assert img[..., :3].std() > 5
    with pytest.raises(ValueError, match="render"):
        viewer.show_volume(images, zs, render="fog", off_screen=True)


def _dihedral(coating):
    from meshladar.meshes import MeshPart
    return ml.Scene.from_parts(
        [MeshPart([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7]], [[0, 1, 2], [0, 2, 3]], 0,
                  "a"),
         MeshPart([[0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], 0,
                  "b")], [coating])


def test_the_bounce_view_colours_a_mirror_dihedral_by_its_second_order(tmp_path, capsys):
    """An aluminium dihedral seen square to its edge at 45° retroreflects: the second order
    dominates every face, and the sampled paths are drawn; a Lambertian ball's faces are
    all single-bounce and no path goes beyond its first hit. The command line draws the
    same."""
    from meshladar.viz import bounce_view

    shown = bounce_view.show_bounces(_dihedral(ALUMINUM), view_vector=(1.0, 1.0, 0.0),
                                     off_screen=True, window_size=(400, 300))
    img = shown.image
    assert _is(img, bounce_view.ORDER_COLORS[1]).sum() > 5000
    assert _is(img, bounce_view.ORDER_COLORS[0]).sum() < 50     # the legend's text edges
    assert _is(img, bounce_view.PATH_COLOR).sum() > 200
    assert shown.legend.labels[0] == "order 2 dominates"
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=3)],
                               [lambertian(0.9)])
    img = bounce_view.show_bounces(ball, view_vector=(0.0, 0.0, 1.0), off_screen=True,
                                   window_size=(400, 300)).image
    assert _is(img, bounce_view.ORDER_COLORS[0]).sum() > 5000
    assert _is(img, bounce_view.ORDER_COLORS[1]).sum() < 50
    path = tmp_path / "dihedral.stl"
    import trimesh
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], float)
    trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]).export(path)
    shot = tmp_path / "bounces.png"
    assert ml.cli.main(["view", str(path), "--material", "aluminum", "--bounces", "2",
                        "--view-angle", "45", "--screenshot", str(shot), "--size",
                        "400x300"]) == 0
    assert shot.stat().st_size > 0 and "wrote" in capsys.readouterr().out
