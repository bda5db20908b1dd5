"""A sensor on a surface: a hit at zero range (or, by rounding, a negative one) cannot be
ranged; it is a miss, in every cast (the one-loop cast, the staged one, the moving
parts'), with either echo model and either way of weighing hits."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.errors import EmptyScanWarning
from meshladar.motion import Motion
from meshladar.raytrace.backends import resolve_backend
from meshladar.scan import Platform, ScanBeam, ScanSensor, raster, rotating, scan
from meshladar.scan._kernels import MIN_RANGE
from meshladar.scan.cast import cast_chunk, cast_static, world_directions

EL = math.radians(5.0)


def _ground(coating=ml.materials.DARK_GRAY, *more):
    """A 100 m square plate in the plane z = 0 (and more parts)."""
    v = np.array([[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]], float)
    return ml.Scene.from_meshes([(trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]]), coating)]
                                + [(m, coating) for m in more])


def _sensor(echoes, divergence=0.0):
    return ScanSensor(pulse_energy=1e-6, aperture_diameter=0.05, sample_rate=2e9,
                      echoes=echoes, beam=ScanBeam(divergence))


@pytest.mark.parametrize("echoes", ["waveform", "discrete"])
@pytest.mark.parametrize("coating", [ml.materials.DARK_GRAY, ml.brdf.Lambertian(0.5)],
                         ids=["weighed-in-the-cast", "weighed-after"])
def test_a_sensor_on_the_plate_ranges_nothing_and_just_above_it_ranges_the_plate(
        echoes, coating):
    """From (0, 0, 0), in the plate, beams 5° down and up meet it at zero range: no return
    (it raised ZeroDivisionError); from 1 cm above, the beam down ranges the plate at
    0.01 / sin 5° = 11.5 cm (true range to 1e-12, its true point on z = 0)."""
    pattern = raster([0.0], [-5.0, 5.0], pulse_rate=1e3)
    with pytest.warns(EmptyScanWarning, match="none of the 2 pulses met the scene"):
        on = scan(_ground(coating), pattern, Platform.static((0, 0, 0)), _sensor(echoes))
    assert len(on) == 0
    above = scan(_ground(coating), pattern, Platform.static((0, 0, 0.01)), _sensor(echoes))
    assert len(above) == 1 and above.points["pulse_id"][0] == 0
    np.testing.assert_allclose(above.points["true_range"], 0.01 / math.sin(EL), rtol=1e-12)
    np.testing.assert_allclose(above.points["true_z"], 0.0, atol=1e-15)


@pytest.mark.parametrize("echoes", ["waveform", "discrete"])
def test_a_spinning_head_on_the_plate_ranges_nothing_and_just_above_it_sees_the_room(echoes):
    """A 16-channel head at z = 0, in the plate that floors a box room: every sub-ray
    starts on the plate, so none is ranged (it raised ZeroDivisionError). 1 cm up, the
    down-looking channels range the plate (z = 0), the others the walls 20 m away."""
    room = trimesh.creation.box((40.0, 40.0, 12.0))
    room.apply_translation((0.0, 0.0, 6.0))       # floor at z = 0, under the plate
    sc = _ground(ml.materials.DARK_GRAY, room)
    elevations = np.linspace(-15, 15, 16)
    pattern = rotating(elevations, rotation_hz=10, pulse_rate=1e5, duration=0.01)
    with pytest.warns(EmptyScanWarning, match=f"none of the {len(pattern)} pulses met"):
        on = scan(sc, pattern, Platform.static((0, 0, 0)), _sensor(echoes, 5e-4))
    assert len(on) == 0
    above = scan(sc, pattern, Platform.static((0, 0, 0.01)), _sensor(echoes, 5e-4))
    first = above.points["return_number"] == 1
    down = elevations[above.points["channel"]] < 0
    assert set(np.unique(above.points["pulse_id"][first])) == set(range(len(pattern)))
    np.testing.assert_allclose(above.points["true_z"][first & down], 0.0, atol=1e-12)
    wall = np.max(np.abs(above.true_xyz[first & ~down, :2]), axis=1)
    np.testing.assert_allclose(wall, 20.0, rtol=1e-9)


def test_a_moving_part_scan_drops_the_hit_at_the_origin_too():
    """With a moving part the staged cast runs part by part: the plate through the origin
    still ends the beams 5° down and up, though the moving crate lies 30 m ahead across
    both; the level beam, in the plate's plane, never meets it and reaches the crate. The
    same returns as without the motion."""
    crate = trimesh.creation.box((2.0, 20.0, 20.0))
    crate.apply_translation((31.0, 0.0, 0.0))
    sc = _ground(ml.materials.DARK_GRAY, crate)
    pattern = raster([0.0], [-5.0, 0.0, 5.0], pulse_rate=1e3)
    still = scan(sc, pattern, Platform.static((0, 0, 0)), _sensor("discrete"))
    moving = scan(sc, pattern, Platform.static((0, 0, 0)), _sensor("discrete"),
                  motions={1: Motion(velocity=(1e-3, 0.0, 0.0))})
    for cloud, shift in ((still, 0.0), (moving, 1e-3 * 1e-3)):
        assert cloud.points["pulse_id"].tolist() == [1]          # the level beam only
        assert cloud.points["true_part"][0] == 1
        np.testing.assert_allclose(cloud.points["true_range"], 30.0 + shift, rtol=1e-9)


@pytest.mark.parametrize("distance, ranged", [(0.0, False), (0.5 * MIN_RANGE, False),
                                              (-0.5 * MIN_RANGE, False),
                                              (10 * MIN_RANGE, True)])
def test_a_hit_within_min_range_is_a_miss_in_both_casts(distance, ranged):
    """A ray 5° down meeting the plate ``distance`` from its origin (a negative one: 5° up
    from under it): within MIN_RANGE (1 µm), face −1, distance inf, cos 0, point nan, in
    the one-loop cast and the staged one alike; 10 µm away, ranged at that distance."""
    sc = _ground()
    height = distance * math.sin(EL)
    up = 1.0 if distance < 0 else -1.0
    local = np.array([[math.cos(EL), 0.0, up * math.sin(EL)]])
    origins = np.array([[0.0, 0.0, height]])
    rot = np.eye(3)[None]
    offsets = np.zeros((1, 2))
    backend = resolve_backend("auto")
    one = cast_static(sc, origins, rot, local, offsets, None, backend)
    two = cast_chunk(sc, origins, world_directions(rot, local, offsets), backend)
    for cast in (one, two):
        if ranged:
            assert cast.face[0, 0] >= 0
            np.testing.assert_allclose(cast.distance[0, 0], distance, rtol=1e-9)
        else:
            assert cast.face[0, 0] == -1 and cast.distance[0, 0] == np.inf
            assert cast.cos[0, 0] == 0.0 and np.isnan(cast.points[0, 0]).all()
    assert two.blocked[0, 0] == (not ranged)
