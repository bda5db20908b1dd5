"""A scan's point cloud drawn over its mesh, off screen for real; the picture's content is
checked at the size it is drawn at."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.scan import Platform, ScanBeam, ScanSensor, rotating, scan

from test_pyvista_viewer import rendering  # noqa: F401  (the off-screen probe)


@pytest.fixture(scope="module")
def room():
    box = trimesh.creation.box((20.0, 20.0, 6.0))
    sc = ml.Scene.from_meshes([(box, ml.brdf.Lambertian(0.5))])
    pat = rotating(np.linspace(-10, 10, 8), rotation_hz=10, pulse_rate=4e4, duration=0.1)
    sen = ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                     beam=ScanBeam(0.0))
    return sc, scan(sc, pat, Platform.static((0.0, 0.0, 0.0)), sen)


def test_points_are_drawn_in_their_colour_map_with_a_titled_bar(room):
    from meshladar.viz import points

    sc, cloud = room
    shown = points.show_points(cloud, sc, color_by="range", off_screen=True,
                               window_size=(400, 300), point_size=6)
    img = shown.image
    assert img.shape[:2] == (300, 400)
    # viridis pixels: green above red and blue (the map's middle), absent from the grey
    # mesh and the white background
    r, g, b = (img[..., i].astype(int) for i in range(3))
    colored = (np.abs(r - g) > 40) | (np.abs(g - b) > 40)
    assert colored.sum() > 500
    assert [bar.title for bar in shown.scalar_bars] == ["range [m]"]


def test_range_errors_draw_on_a_diverging_map_and_bad_fields_are_refused(room):
    from meshladar.viz import points

    sc, cloud = room
    bars = points.show_points(cloud, sc, color_by="range_error", off_screen=True,
                              window_size=(300, 200)).scalar_bars
    assert bars[0].title == "range error [m]"
    with pytest.raises(ParameterError, match="color_by"):
        points.show_points(cloud, sc, color_by="colour", off_screen=True)
    with pytest.raises(ParameterError, match="cloud"):
        points.show_points(cloud.points, sc, off_screen=True)


def test_a_patterns_footprint_is_drawn_by_channel(room):
    from meshladar.viz import points

    sc, cloud = room
    shown = points.show_points(cloud, sc, color_by="channel", off_screen=True,
                               window_size=(300, 200))
    assert shown.scalar_bars[0].title == "channel"
