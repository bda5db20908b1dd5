"""Points of a moving scanner on the mesh, checked with the scene's own closed-form
geometry (the signed distance of boxes), and the files' round trips."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.scan import (Platform, ScanBeam, ScanSensor, read_hdf5, read_las, rotating,
                            scan, write_hdf5, write_las)

ROOM = np.array([20.0, 20.0, 6.0])                      # half sizes
CRATE_C, CRATE_H = np.array([8.0, 3.0, -1.0]), np.array([2.0, 3.0, 1.5])


def _box_distance(p, c, h):
    q = np.abs(p - c) - h
    return np.where(np.all(q <= 0, axis=1), -q.max(axis=1),
                    np.linalg.norm(np.maximum(q, 0), axis=1))


def _surface_distance(p):
    return np.minimum(np.abs(_box_distance(p, 0.0, ROOM)),
                      np.abs(_box_distance(p, CRATE_C, CRATE_H)))


@pytest.fixture(scope="module")
def cloud():
    """A 32-channel head at 10 Hz, 3e5 pulses/s, 16 sub-rays, moving at 10 m/s through a
    room with a crate: 0.1 s, 30 000 pulses."""
    room = trimesh.creation.box(2 * ROOM)
    crate = trimesh.creation.box(2 * CRATE_H)
    crate.apply_translation(CRATE_C)
    coat = ml.brdf.Lambertian(0.4)
    sc = ml.Scene.from_meshes([(room, coat), (crate, coat)])
    pat = rotating(np.linspace(-15, 15, 32), rotation_hz=10, pulse_rate=3e5, duration=0.1)
    sen = ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                     beam=ScanBeam(5e-4, sub_rays=16))
    return scan(sc, pat, Platform.moving((0, 0, 0), (10.0, 0, 0)), sen, keep_waveforms=True)


def test_every_point_lies_on_the_mesh_within_a_fraction_of_the_range_resolution(cloud):
    """Distances to the boxes' surfaces, from their closed form: RMS ≤ 1 % and max ≤ 10 %
    of a sample's range c Δt / 2 (7.5 cm; measured 0.3 mm RMS, 3.7 mm max, at edges
    where a footprint spans two faces); the true points lie on the surface to 1e-9 m."""
    resolution = 0.5 * 299_792_458.0 / 2e9
    assert len(cloud) >= 30_000
    d = _surface_distance(cloud.xyz)
    assert np.sqrt(np.mean(d ** 2)) <= 0.01 * resolution
    assert d.max() <= 0.10 * resolution
    truth = cloud.true_xyz[cloud.points["true_face"] >= 0]
    assert len(truth) == len(cloud)
    # the photoelectron-weighted true point of a footprint on one face lies on it
    one_face = cloud.points["number_of_returns"] == 1
    assert np.median(_surface_distance(cloud.true_xyz[one_face])) <= 1e-9


def test_each_pulse_leaves_from_the_platforms_pose_at_its_own_time(cloud):
    """The range is measured from where the platform was when the pulse left: the distance
    from (10 m/s × emission time, 0, 0) to the point equals the measured range."""
    pts = cloud.points
    origin = np.stack([10.0 * pts["emission_time"], 0 * pts["x"], 0 * pts["x"]], 1)
    np.testing.assert_allclose(np.linalg.norm(cloud.xyz - origin, axis=1), pts["range"],
                               rtol=1e-12)


def test_las_round_trip(cloud, tmp_path):
    """Every field back exactly, x, y, z within the scale's half step."""
    path = tmp_path / "points.las"
    write_las(path, cloud, scale=1e-4)
    back = read_las(path)
    for name in cloud.points.dtype.names:
        if name in ("x", "y", "z"):
            np.testing.assert_allclose(back.points[name], cloud.points[name], atol=0.5e-4 + 1e-9)
        else:
            assert np.array_equal(back.points[name], cloud.points[name], equal_nan=True), name


def test_laz_and_hdf5_round_trips_are_exact(cloud, tmp_path):
    write_las(tmp_path / "p.laz", cloud)
    assert np.array_equal(read_las(tmp_path / "p.laz").points["range"], cloud.points["range"])
    write_hdf5(tmp_path / "p.h5", cloud)
    back = read_hdf5(tmp_path / "p.h5")
    assert back.points.tobytes() == cloud.points.tobytes()
    assert len(back.waveforms) == len(cloud.waveforms) == 4     # 30 000 pulses, 8192 a chunk
    for a, b in zip(back.waveforms + back.starts, cloud.waveforms + cloud.starts):
        assert np.array_equal(a, b)
    assert back.info["conventions"] == cloud.info["conventions"]


def test_writing_never_leaves_a_partial_file(cloud, tmp_path, monkeypatch):
    """A write that fails midway keeps the existing file as it was."""
    path = tmp_path / "p.las"
    path.write_bytes(b"user's file")
    import laspy

    def boom(self, *a, **k):
        raise OSError("disk full")
    monkeypatch.setattr(laspy.LasData, "write", boom)
    with pytest.raises(OSError):
        write_las(path, cloud)
    assert path.read_bytes() == b"user's file"


def test_a_missing_writer_is_named_before_any_work(monkeypatch, tmp_path):
    """Without laspy (or lazrs for .laz, h5py for .h5) ``meshladar scan`` stops before
    scanning, naming the package and the extra."""
    import importlib.util

    from meshladar.cli import main
    from meshladar.errors import ParameterError
    from meshladar.scan.formats import check_writable

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name in ("lazrs", "laszip", "h5py")
                        else real(name, *a))
    check_writable("p.las")
    for name in ("p.laz", "p.h5"):
        with pytest.raises(ParameterError, match=r"meshladar\[scan\]"):
            check_writable(name)
    import meshladar.cli.scan as cli_scan
    monkeypatch.setattr(cli_scan.scanning, "scan", lambda *a, **k: pytest.fail("scanned"))
    trimesh.creation.box((2.0, 2.0, 2.0)).export(tmp_path / "b.stl")
    assert main(["scan", str(tmp_path / "b.stl"), "--quiet", "-o", str(tmp_path / "p.laz"),
                 "--pattern", "raster azimuth_deg=0 elevation_deg=0 pulse_rate=1",
                 "--platform", "static position=-5,0,0"]) == 2


@pytest.mark.parametrize("sub_rays, pitch", [(7, None), (16, None), (4, 1e-3)])
def test_the_one_loop_cast_gives_the_staged_casts_hits_number_for_number(sub_rays, pitch):
    """A static scan's cast in one compiled loop (directions, packets and refinement per
    pulse) against the sub-ray directions made first and cast with the backend's ``run``:
    the same faces, distances, cosines and points bit for bit, for packets that span
    pulses (7 sub-rays at width 16), one pulse a packet, and a flash pixel's offsets; in
    a room far from the origin (Embree's scene at a scale other than 1)."""
    from meshladar.raytrace.backends import resolve_backend
    from meshladar.scan.cast import cast_chunk, cast_static, world_directions

    room = trimesh.creation.box(2 * ROOM)
    room.apply_translation((3e4, -2e4, 10.0))
    sc = ml.Scene.from_meshes([(room, ml.brdf.Lambertian(0.4))])
    rng = np.random.default_rng(11)
    n = 500
    origins = np.array([3e4, -2e4, 10.0]) + rng.uniform(-5, 5, (n, 3))
    rot = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    local = rng.normal(size=(n, 3))
    local[:, 0] = np.abs(local[:, 0]) + 0.5                      # forward (a flash's x > 0)
    local /= np.linalg.norm(local, axis=1)[:, None]
    offsets = rng.uniform(-0.5, 0.5, (sub_rays, 2)) * (1.0 if pitch else 2e-3)
    backend = resolve_backend("auto")
    one = cast_static(sc, origins, rot, local, offsets, pitch, backend)
    two = cast_chunk(sc, origins, world_directions(rot, local, offsets, pitch), backend)
    assert (one.face >= 0).all()                                 # inside the room
    for name in ("face", "distance", "cos", "points"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))


#: Sub-ray directions against numpy's: a few ulp of a unit vector (measured 7.8e-16, the
#: flash's; a beam's 5.6e-16).
DIRECTION_ULP = 1e-15


@pytest.mark.parametrize("pitch", [None, 2e-3])
def test_sub_ray_directions_are_the_turned_offsets_normalised(pitch):
    """:func:`world_directions` against numpy written here from its definition: a beam's
    sub-ray is R (d + tan a u + tan b v) normalised, u = z × d normalised (y × d where d is
    near z), v = d × u; a flash pixel's R (1, d_y/d_x + a p, d_z/d_x + b p) normalised.
    Unit vectors, each component within DIRECTION_ULP, for directions of every kind
    (some near ±z, some not of unit length as given: a beam's d is normalised first; the
    kernel once took a pulse's length for 1, and a direction of length 2 got half its
    sub-rays' spread)."""
    from meshladar.scan.cast import world_directions

    rng = np.random.default_rng(5)
    n, m = 400, 9
    rot = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    local = rng.normal(size=(n, 3))
    local[:, 0] = np.abs(local[:, 0]) + 0.2
    local[:40] = [0.01, 0.02, 1.0]                              # near +z: u from y
    local *= rng.uniform(0.5, 2.0, (n, 1)) if pitch is None else 1.0
    offsets = rng.uniform(-1e-2, 1e-2, (m, 2)) if pitch is None else rng.uniform(-1, 1, (m, 2))
    got = world_directions(rot, local, offsets, pitch)
    if pitch is None:
        d = local / np.linalg.norm(local, axis=1)[:, None]
        ref = np.where(np.abs(d[:, 2:]) < 0.9, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0])
        u = np.cross(ref, d)
        u /= np.linalg.norm(u, axis=1)[:, None]
        v = np.cross(d, u)
        t = np.tan(offsets)
        s = d[:, None] + t[None, :, :1] * u[:, None] + t[None, :, 1:] * v[:, None]
    else:
        s = np.stack(np.broadcast_arrays(
            1.0, local[:, None, 1] / local[:, None, 0] + offsets[None, :, 0] * pitch,
            local[:, None, 2] / local[:, None, 0] + offsets[None, :, 1] * pitch), -1)
    want = np.einsum("nij,nkj->nki", rot, s / np.linalg.norm(s, axis=2)[..., None])
    assert np.abs(got - want).max() < DIRECTION_ULP
    assert np.abs(np.linalg.norm(got, axis=2) - 1.0).max() < DIRECTION_ULP


@pytest.mark.parametrize("coating, extinction", [
    (ml.brdf.Lambertian(0.4), 0.0),
    (ml.brdf.SandfordRobertson(rho_d=0.05, epsilon=0.4, b=0.5, e=0.1), 2e-3),
    (ml.brdf.Phong(0.3, 0.2, 20.0), 0.0)])
def test_the_one_loop_cast_weighs_its_hits_as_the_link_budget_does(coating, extinction):
    """Photoelectrons weighed in the one-loop cast against the link budget written here
    with the coating's numpy model (``projected``): to 1e-13 for SR (its compiled twin),
    and :func:`photoelectrons` on the same hits bit for bit, a Lambertian's bit for bit
    with its numpy model too; a coating without a compiled row (Phong) is not weighed in
    the loop (None: the staged budget), which then agrees with the model too."""
    from meshladar.raytrace.backends import resolve_backend
    from meshladar.scan.cast import cast_static, photoelectrons

    room = trimesh.creation.box(2 * ROOM)
    sc = ml.Scene.from_meshes([(room, coating)])
    sensor = ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                        extinction=extinction, beam=ScanBeam(5e-4, sub_rays=7))
    rng = np.random.default_rng(12)
    n = 400
    origins = rng.uniform(-5, 5, (n, 3))
    rot = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    local = rng.normal(size=(n, 3))
    local /= np.linalg.norm(local, axis=1)[:, None]
    offsets = rng.uniform(-1e-3, 1e-3, (7, 2))
    shares = rng.uniform(0.05, 0.3, 7)
    cast = cast_static(sc, origins, rot, local, offsets, None, resolve_backend("auto"),
                       sensor, shares)
    c = np.minimum(cast.cos, 1.0)
    photon = 6.62607015e-34 * 299792458.0 / sensor.wavelength
    budget = (1e-7 * np.pi * 0.05 ** 2 / 4 * sensor.optics_transmission
              * sensor.quantum_efficiency / photon)
    want = (budget * shares * coating.projected(c, np.sqrt(1 - c * c))
            / cast.distance ** 2 * np.exp(-2 * extinction * cast.distance))
    staged = photoelectrons(sc, cast, shares, sensor)
    assert (want > 0).all()
    np.testing.assert_allclose(staged, want, rtol=1e-13, atol=0)
    if isinstance(coating, ml.brdf.Phong):
        assert cast.pe is None
        return
    np.testing.assert_array_equal(cast.pe, staged)
    if isinstance(coating, ml.brdf.Lambertian):
        np.testing.assert_array_equal(cast.pe, want)
