"""Point files beyond their round trips: strict JSON in HDF5, LAS 1.4's global encoding,
coordinates that need a coarser LAS scale, paths refused before writing, and a flash
cloud's frames."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.scan import (GeigerMode, Platform, PointCloud, flash, read_hdf5, read_las,
                            scan, write_hdf5, write_las)
from meshladar.scan.points import POINT_DTYPE

from _scan_scenes import plate, scene, sensor


def _strict(text):
    def refuse(constant):
        raise ValueError(f"not strict JSON: {constant}")
    return json.loads(text, parse_constant=refuse)


def _cloud(x, info=None):
    pts = np.zeros(len(x), POINT_DTYPE)
    pts["x"], pts["y"], pts["z"] = x, 4e6, 100.0
    pts["return_number"] = pts["number_of_returns"] = 1
    return PointCloud(pts, info or {})


def test_a_geiger_scans_info_is_strict_json_and_reads_back_its_infinite_dead_time(tmp_path):
    """dead_time=inf was written as JSON's non-standard ``Infinity``: now the string
    "inf", a float again when read (as are -inf and nan anywhere in the info)."""
    h5py = pytest.importorskip("h5py")
    geiger = sensor(pulse_energy=1e-12, geiger=GeigerMode(shots=10))
    cloud = scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
                 geiger)
    cloud = PointCloud(cloud.points, dict(cloud.info, extra=[-math.inf, math.nan]))
    write_hdf5(tmp_path / "g.h5", cloud)
    with h5py.File(tmp_path / "g.h5", "r") as f:
        raw = _strict(f.attrs["info"])
    assert raw["sensor"]["geiger"]["dead_time_s"] == "inf"
    assert raw["extra"] == ["-inf", "nan"]
    back = read_hdf5(tmp_path / "g.h5").info
    assert back["sensor"]["geiger"]["dead_time_s"] == math.inf
    assert back["extra"][0] == -math.inf and math.isnan(back["extra"][1])
    assert back["sensor"]["geiger"]["shots"] == 10


def test_numpy_numbers_and_arrays_in_the_info_read_back_as_numbers(tmp_path):
    """HDF5 wrote numpy's numbers through ``str`` (np.float32(1.5) came back as "1.5"):
    now as JSON's numbers and lists, as the .npz writer does; non-finite ones as strings."""
    pytest.importorskip("h5py")
    info = {"gain": np.float32(1.5), "n": np.int64(3), "axis": np.array([0.0, np.inf]),
            "flag": np.bool_(True), "t": (np.float64(-np.inf), 2), "long": np.longdouble(2.5)}
    write_hdf5(tmp_path / "n.h5", _cloud([0.0], info))
    back = read_hdf5(tmp_path / "n.h5").info
    assert back == {"gain": 1.5, "n": 3, "axis": [0.0, math.inf], "flag": True,
                    "t": [-math.inf, 2], "long": 2.5}
    assert type(back["gain"]) is float and type(back["n"]) is int


def test_las_14_format_6_sets_the_wkt_bit_of_its_global_encoding(tmp_path):
    """LAS 1.4 R15 §2.4: bit 4 (WKT) must be set for point formats 6-10."""
    laspy = pytest.importorskip("laspy")
    write_las(tmp_path / "p.las", _cloud([0.0, 1.0]))
    header = laspy.read(tmp_path / "p.las").header
    assert header.point_format.id == 6 and header.global_encoding.wkt
    raw = (tmp_path / "p.las").read_bytes()
    assert int.from_bytes(raw[6:8], "little") & 16 == 16


def test_a_cloud_spanning_300_km_is_written_at_a_coarser_scale_that_fits_int32(tmp_path):
    """500 km to 800 km east (a UTM strip): 1e-4 m steps would overflow LAS's int32, so
    the default scale is 1e-3 (2,147 km), the points back to half of it; a scale the user
    gives that is too fine is refused naming the finest that fits."""
    pytest.importorskip("laspy")
    x = np.array([500000.12345, 500100.0, 800000.0])
    write_las(tmp_path / "big.las", _cloud(x))
    back = read_las(tmp_path / "big.las")
    np.testing.assert_allclose(back.points["x"], x, atol=0.5e-3 + 1e-9)
    assert np.abs(back.points["x"] - x).max() > 0.5e-4          # not the 1e-4 default
    with pytest.raises(ParameterError, match=r"scale=0\.0001 is too fine .* give scale "
                                             r">= 0\.00014"):
        write_las(tmp_path / "big2.las", _cloud(x), scale=1e-4)
    write_las(tmp_path / "small.las", _cloud(x[:2]))               # 100 m: 1e-4 kept
    np.testing.assert_allclose(read_las(tmp_path / "small.las").points["x"], x[:2],
                               atol=0.5e-4 + 1e-9)


@pytest.mark.parametrize("write", [write_las, write_hdf5])
def test_a_folder_or_a_missing_folder_is_refused_before_writing(tmp_path, write):
    pytest.importorskip("laspy" if write is write_las else "h5py")
    with pytest.raises(ParameterError, match=r"path: .* is a folder; name a file in it"):
        write(tmp_path, _cloud([0.0]))
    with pytest.raises(ParameterError, match=r"path: no folder .*nowhere"):
        write(tmp_path / "nowhere" / "p.las", _cloud([0.0]))


def test_a_flash_image_refuses_a_frame_it_does_not_hold():
    """Two frames: frame 1 is the plate at 50 m; frame 2 and −1 are refused with the
    valid range (they gave all-nan images), as is return 0."""
    cloud = scan(scene(plate(50.0)), flash(3, 4, ifov_deg=0.1, frames=2),
                 Platform.static((0, 0, 0)), sensor())
    np.testing.assert_allclose(cloud.image("range", frame=1), 50.0, rtol=1e-4)
    for frame in (2, -1, 0.5):
        with pytest.raises(ParameterError, match=r"frame must be an integer in \[0, 1\] "
                                                 r"\(the cloud's 2 frames"):
            cloud.image("range", frame=frame)
    with pytest.raises(ParameterError, match="return_number"):
        cloud.image("range", return_number=0)


def test_a_points_files_extension_names_its_format_for_every_writer_and_reader(tmp_path):
    """One table of extensions: .las/.laz are LAS, .h5/.hdf5 HDF5 whatever their case,
    anything else none; each writer refuses the other's extensions naming that writer."""
    from meshladar.scan.formats import points_format
    named = {p: points_format(p) for p in ("a.las", "b.LAZ", "c.h5", "d.HDF5", "e.txt",
                                           "f", "g.las.bak")}
    assert named == {"a.las": "LAS", "b.LAZ": "LAS", "c.h5": "HDF5", "d.HDF5": "HDF5",
                     "e.txt": None, "f": None, "g.las.bak": None}
    with pytest.raises(ParameterError, match=r"path: .*'\S*x\.H5' names an HDF5 file; "
                                             "write_hdf5 writes that format"):
        write_las(str(tmp_path / "x.H5"), _cloud([0.0]))
    with pytest.raises(ParameterError, match=r"path: .*x\.laz' names a LAS file; "
                                             "write_las writes that format"):
        write_hdf5(str(tmp_path / "x.laz"), _cloud([0.0]))
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("photoelectrons, per_pe", [
    ([0.4, 7.0, 65535.0], 1.0),                             # the brightest fits: as counted
    ([3e3, 1.2e5, 2.4e6], 65535.0 / 2.4e6),                 # normalised to the brightest
    ([np.nan, 1.2e5, 2.4e6], 65535.0 / 2.4e6),              # a non-finite one: no say, 0
    ([np.inf, 7.0, 100.0], 1.0),
])
def test_las_intensity_is_photoelectrons_normalised_to_16_bits_with_its_factor(
        tmp_path, photoelectrons, per_pe):
    """LAS's intensity is the photoelectrons times 1, or 65535 over the brightest where it
    would not fit (a user's room scan clipped 98 % of its points at 65535, its intensity
    useless), the factor in the meshladar VLR as a float64; the exact count reads back."""
    import struct

    laspy = pytest.importorskip("laspy")
    cloud = _cloud([0.0, 1.0, 2.0])
    cloud.points["intensity"] = photoelectrons
    write_las(tmp_path / "p.las", cloud)
    las = laspy.read(tmp_path / "p.las")
    (vlr,) = [v for v in las.vlrs if (v.user_id, v.record_id) == ("meshladar", 1)]
    assert struct.unpack("<d", vlr.record_data) == (per_pe,)
    np.testing.assert_array_equal(las.intensity, np.nan_to_num(
        np.rint(np.array(photoelectrons) * per_pe), nan=0.0, posinf=0.0))
    np.testing.assert_array_equal(read_las(tmp_path / "p.las").points["intensity"],
                                  cloud.points["intensity"])          # float32, exact


def test_a_geiger_arrays_records_are_labelled_detections(tmp_path):
    """A Geiger-mode array's records count detections over its shots, not photoelectrons
    (a user's trial read "photoelectrons per sample" on integer counts): streamed during
    the scan or written after it; a linear receiver's are photoelectrons."""
    h5py = pytest.importorskip("h5py")
    geiger = sensor(pulse_energy=1e-12, geiger=GeigerMode(shots=10))
    frame, at = flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0))
    scan(scene(plate(50.0)), frame, at, geiger, waveforms_file=tmp_path / "s.h5")
    write_hdf5(tmp_path / "w.h5", scan(scene(plate(50.0)), frame, at, geiger,
                                       keep_waveforms=True))
    write_hdf5(tmp_path / "l.h5", scan(scene(plate(50.0)), frame, at, sensor(),
                                       keep_waveforms=True))
    for name, units in (("s", "detections per sample over each pulse's shots; starts: s"),
                        ("w", "detections per sample over each pulse's shots; starts: s"),
                        ("l", "photoelectrons per sample; starts: s")):
        with h5py.File(tmp_path / f"{name}.h5", "r") as f:
            assert f["waveforms"].attrs["units"] == units, name
            if name != "l":
                block = np.concatenate([f["waveforms"][k][()].ravel()
                                        for k in f["waveforms"] if k.startswith("block")])
                np.testing.assert_array_equal(block, np.rint(block))     # counts


def _foreign_las(path, point_format):
    """A LAS file as another tool writes it (laspy directly, no meshladar field)."""
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=point_format, version="1.4" if point_format >= 6
                             else "1.2")
    header.scales, header.offsets = [0.001] * 3, [0.0] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = np.array([[1.0, 2.0, 3.0], [0.5, 0.25, 0.0], [-1.0, 0.0, 1.0]])
    las.intensity = np.array([10, 2000, 65535], np.uint16)
    las.return_number = np.array([1, 1, 2], np.uint8)
    las.number_of_returns = np.array([1, 2, 2], np.uint8)
    if point_format >= 6:
        las.scan_angle = np.array([-5000, 0, 5000], np.int16)
        las.gps_time = np.array([10.0, 10.5, 11.0])
    else:
        las.scan_angle_rank = np.array([-30, 0, 30], np.int8)
    las.write(path)


@pytest.mark.parametrize("point_format, angles, times", [
    (6, [-30.0, 0.0, 30.0], [10.0, 10.5, 11.0]), (0, [-30.0, 0.0, 30.0], None)])
def test_another_tools_las_reads_with_its_own_fields_when_asked(tmp_path, point_format,
                                                                 angles, times):
    """A user's trial: a LAS of another tool could not be drawn over the scene at all. It
    is refused as not meshladar's, naming foreign=True; with it, LAS's own fields come back
    (scan angle from LAS 1.4's 0.006° steps or an old format's degrees, GPS time as the
    emission time where the format has one) and the rest are NaN or -1, listed in info."""
    path = tmp_path / "other.las"
    _foreign_las(path, point_format)
    with pytest.raises(ParameterError, match=r"not a meshladar point cloud .*foreign=True"):
        read_las(path)
    cloud = read_las(path, foreign=True)
    pts = cloud.points
    np.testing.assert_allclose(cloud.xyz, [[1.0, 0.5, -1.0], [2.0, 0.25, 0.0], [3.0, 0, 1.0]])
    np.testing.assert_array_equal(pts["intensity"], [10, 2000, 65535])
    np.testing.assert_array_equal(pts["number_of_returns"], [1, 2, 2])
    np.testing.assert_allclose(pts["scan_angle"], angles, rtol=1e-6)
    assert cloud.info["foreign"] and cloud.info["intensity_units"] == "LAS intensity"
    assert ("emission_time" in cloud.info["fields"]) == (times is not None)
    if times is not None:
        np.testing.assert_array_equal(pts["emission_time"], times)
    assert np.isnan(pts["range"]).all() and np.isnan(pts["true_range"]).all()
    assert (pts["true_part"] == -1).all() and (pts["true_face"] == -1).all()
