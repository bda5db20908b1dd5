"""Point-cloud files: LAS 1.4 (through laspy; LAZ when its lazrs backend is installed) and
HDF5 (through h5py), both written atomically and read without pickle.

LAS: point format 6 (its global encoding's WKT bit set, as LAS 1.4 requires of formats
6-10) with every field of :data:`~meshladar.scan.points.POINT_FIELDS` that LAS lacks as a
named extra-bytes dimension (its unit in the description): x, y, z are stored as 32-bit
integers at ``scale`` (default 0.1 mm, coarser where the cloud spans more than 2³¹ − 1
steps: :func:`write_las`) from an offset at the cloud's minimum, so they read back within
``scale``/2; LAS's own intensity is the photoelectrons times :func:`las_intensity_scale`
(1 where the brightest fits 16 bits, else 65535 over it), rounded, the factor recorded in
a VLR (:data:`INTENSITY_VLR`) and the exact value in the ``photoelectrons`` extra bytes;
its scan angle the pattern's in LAS's 0.006° steps, its GPS time the emission time plus
the platform's ``time_origin`` (a trajectory file's ``time_offset``; s). Every extra-bytes
field reads back exactly (:data:`EXTRA_NAMES`: the exact intensity and scan angle).

HDF5: ``/points`` is one compound dataset of the records (each field's unit in the
attribute ``units``, a JSON object); when the cloud holds waveforms, the group
``/waveforms`` holds one dataset per block of consecutive pulses, ``block_<first pulse, 12
digits>`` (pulses × samples, its ``first_pulse`` as an attribute; the group's ``units``
:data:`RECORD_UNITS`: photoelectrons per sample, a Geiger-mode array's detections) and
their starts ``starts_<first pulse>`` (s); the root's ``info`` attribute holds the scan's parameters as
strict JSON (a non-finite number, such as a Geiger-mode dead time of inf, as the string
``"inf"``, ``"-inf"`` or ``"nan"``, read back as the float). Everything reads back exactly.
"""

from __future__ import annotations

import json
import math
import os
import struct
import threading

import numpy as np

from .._atomic_write import make_temporary, write_atomic
from .._validate import check_path, check_real
from ..errors import ParameterError
from .formats import _not_named_as, _target, check_writable
from .foreign import LAS_SCAN_ANGLE_STEP, foreign_points
from .points import POINT_DTYPE, POINT_FIELDS, PointCloud

__all__ = ["write_las", "read_las", "write_hdf5", "read_hdf5", "las_intensity_scale",
           "LAS_NATIVE", "EXTRA_NAMES", "INTENSITY_VLR", "RECORD_UNITS", "WaveformSink",
           "NON_FINITE"]

#: The record fields LAS 1.4 stores in its own dimensions (all others are extra bytes).
LAS_NATIVE = ("x", "y", "z", "return_number", "number_of_returns")
#: The largest coordinate LAS stores, in steps of its scale (a signed 32-bit integer).
_LAS_STEPS = 2 ** 31 - 1
#: LAS intensity's largest value (16 bits).
_LAS_INTENSITY_TOP = 65535
#: The strings that stand for the non-finite floats in the HDF5 file's strict JSON.
NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}
#: Extra-bytes names of the fields whose own names LAS's format 6 takes: the exact
#: photoelectrons (LAS's intensity is 16 bits) and the exact scan angle (LAS's is in steps).
EXTRA_NAMES = {"intensity": "photoelectrons", "scan_angle": "scan_angle_deg"}


def _extra(name):
    return EXTRA_NAMES.get(name, name)


def _need(module):
    try:
        return __import__(module)
    except ImportError:
        raise ParameterError(f"{module} is not installed: pip install 'meshladar[scan]'") \
            from None


def _readable(path, what):
    """``path`` checked to be an existing file before a reader opens it."""
    path = check_path("path", path)
    if os.path.isdir(path):
        raise ParameterError(f"path: {path!r} is a folder, not a {what} file")
    if not os.path.isfile(path):
        raise ParameterError(f"path: no such file {path!r}")
    return path


def _unreadable(path, what, exc):
    first = (str(exc).splitlines() or [type(exc).__name__])[0][:100]
    return ParameterError(f"path: {path!r} is not a {what} file ({first})")


#: The VLR that records LAS intensity's units (user id, record id): its data the
#: little-endian float64 LAS intensity per photoelectron.
INTENSITY_VLR = ("meshladar", 1)


def las_intensity_scale(photoelectrons):
    """LAS intensity per photoelectron: 1 where the brightest return fits LAS's 16 bits,
    else 65535 over it (the LAS specification's normalisation to the data's dynamic range:
    at 1, a scan's strong returns all read 65535); non-finite values are left out (and
    written as 0).

    Parameters
    ----------
    photoelectrons : numpy.ndarray
        The returns' ``intensity``.

    Returns
    -------
    float
    """
    pe = np.asarray(photoelectrons, np.float64)
    top = float(np.max(pe[np.isfinite(pe)], initial=0.0))       # a non-finite one: no say
    return 1.0 if top <= _LAS_INTENSITY_TOP else _LAS_INTENSITY_TOP / top


def write_las(path, cloud, *, scale=None):
    """Write ``cloud`` to a LAS 1.4 file (LAZ if ``path`` ends in ``.laz``), atomically.

    Parameters
    ----------
    path : str or os.PathLike
        The file; an existing file is replaced only once the new one is complete.
    cloud : PointCloud
        The returns.
    scale : float, optional
        The coordinates' resolution (scene units, in [1e-9, 1]). Coordinates are 32-bit
        integers from an offset at the cloud's minimum, so a scale covers a span of
        2³¹ − 1 of its steps: by default 1e-4 (214 km), or the smallest power of ten that
        covers the cloud's span (1e-3 to 2,147 km, ...).

    Raises
    ------
    ParameterError
        Before anything is written: when ``path`` is a folder, in a folder that does not
        exist, or ends in .h5, .hdf5 (:func:`write_hdf5`'s) or .npz (``write_npz``'s),
        ``cloud`` is not a PointCloud, or ``scale`` is out of range or too fine for the
        cloud's span (the message names the finest scale that fits).
    """
    laspy = _need("laspy")
    path = _not_named_as(check_writable(path, "path"), "LAS")
    if not isinstance(cloud, PointCloud):
        raise ParameterError(f"cloud must be a PointCloud; got {type(cloud).__name__}")
    pts = cloud.points
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.global_encoding.wkt = True        # LAS 1.4: required of point formats 6-10
    xyz = cloud.xyz
    header.offsets = np.floor(xyz.min(axis=0)) if len(pts) else np.zeros(3)
    header.scales = np.full(3, _las_scale(xyz, header.offsets, scale))
    header.add_extra_dims([laspy.ExtraBytesParams(
        name=_extra(n), type=np.dtype(t), description=f"{u or 'count'}"[:31])
        for n, t, u, _ in POINT_FIELDS if n not in LAS_NATIVE])
    las = laspy.LasData(header)
    las.x, las.y, las.z = xyz.T
    las.return_number = np.clip(pts["return_number"], 1, 15)
    las.number_of_returns = np.clip(pts["number_of_returns"], 1, 15)
    per_pe = las_intensity_scale(pts["intensity"])
    scaled = np.nan_to_num(pts["intensity"] * per_pe, nan=0.0, posinf=0.0, neginf=0.0)
    las.intensity = np.clip(np.rint(scaled), 0, _LAS_INTENSITY_TOP).astype(np.uint16)
    las.vlrs.append(laspy.VLR(user_id=INTENSITY_VLR[0], record_id=INTENSITY_VLR[1],
                              description="LAS intensity per photoelectron",
                              record_data=struct.pack("<d", per_pe)))
    las.scan_angle = np.clip(np.rint(pts["scan_angle"] / LAS_SCAN_ANGLE_STEP), -30000,
                             30000).astype(np.int16)
    # GPS time: the platform's clock (a trajectory's time_offset) plus the emission time
    las.gps_time = pts["emission_time"] + cloud.info.get("platform", {}).get("time_origin_s",
                                                                            0.0)
    for n, _, _, _ in POINT_FIELDS:
        if n not in LAS_NATIVE:
            las[_extra(n)] = pts[n]
    compress = str(path).lower().endswith(".laz")
    write_atomic(path, lambda fh: las.write(fh, do_compress=compress))


def _las_scale(xyz, offsets, scale):
    """:func:`write_las`'s scale: the user's, checked to cover the cloud's span from
    ``offsets`` in 2³¹ − 1 steps, or the default's."""
    span = float(np.max(xyz - offsets)) if len(xyz) else 0.0
    need = span / (_LAS_STEPS - 1)                   # a step's margin for the rounding
    if scale is None:
        scale = 1e-4 if need <= 1e-4 else 10.0 ** math.ceil(math.log10(need))
        if scale > 1.0:
            raise ParameterError(f"cloud: its coordinates span {span:.6g} from their "
                                 "minimum, more than LAS's 2³¹ − 1 steps of scale 1")
        return scale
    scale = check_real("scale", scale, low=1e-9, high=1.0)
    if scale < need:
        raise ParameterError(f"scale={scale:g} is too fine for this cloud: its coordinates "
                             f"span {span:.6g} from their minimum, more than LAS's 2³¹ − 1 "
                             f"steps; give scale >= {need:.3g} (or leave it out)")
    return scale


def read_las(path, *, foreign=False):
    """Read a LAS/LAZ file that :func:`write_las` wrote back into a :class:`PointCloud`.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    foreign : bool
        Read another tool's LAS file too (one without meshladar's fields): its own
        fields only (:func:`meshladar.scan.foreign.foreign_points`), for drawing it.

    Returns
    -------
    PointCloud
        x, y, z as quantised; every other field exact; ``info`` names the file and the
        platform's time origin (``info["platform"]["time_origin_s"]``: GPS time less
        emission time), so the cloud written again keeps its GPS times.

    Raises
    ------
    ParameterError
        When the file is missing, a folder, not LAS/LAZ, or lacks meshladar's fields
        (unless ``foreign``).
    """
    laspy = _need("laspy")
    path = _readable(path, "LAS/LAZ")
    try:
        las = laspy.read(path)
    except (OSError, laspy.errors.LaspyException, ValueError) as exc:
        raise _unreadable(path, "LAS/LAZ", exc) from None
    names = set(las.point_format.extra_dimension_names)
    missing = [_extra(n) for n, *_ in POINT_FIELDS if n not in LAS_NATIVE
               and _extra(n) not in names]
    if missing and foreign:
        return foreign_points(las, path)
    if missing:
        raise ParameterError(f"{path}: not a meshladar point cloud (no {missing[0]!r} field; "
                             "another tool's LAS reads with foreign=True)")
    pts = np.zeros(len(las.points), POINT_DTYPE)
    pts["x"], pts["y"], pts["z"] = np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)
    pts["return_number"] = np.asarray(las.return_number)
    pts["number_of_returns"] = np.asarray(las.number_of_returns)
    for n, *_ in POINT_FIELDS:
        if n not in LAS_NATIVE:
            pts[n] = np.asarray(las[_extra(n)])
    # the platform's time origin, GPS time less emission time (written again as it was)
    origin = float(np.median(np.asarray(las.gps_time) - pts["emission_time"])) if len(pts) \
        else 0.0
    return PointCloud(pts, {"file": os.fspath(path), "platform": {"time_origin_s": origin}})


def write_hdf5(path, cloud):
    """Write ``cloud`` (records, waveforms if held, info) to an HDF5 file, atomically
    (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file; an existing one is replaced only once the new one is complete.
    cloud : PointCloud
        The returns.

    Raises
    ------
    ParameterError
        Before anything is written: when ``path`` is a folder, in a folder that does not
        exist, or ends in .las, .laz (:func:`write_las`'s) or .npz (``write_npz``'s), or
        ``cloud`` is not a PointCloud.
    """
    h5py = _need("h5py")
    path = _not_named_as(_target(path, "path"), "HDF5")
    if not isinstance(cloud, PointCloud):
        raise ParameterError(f"cloud must be a PointCloud; got {type(cloud).__name__}")

    def fill(fh):
        with h5py.File(fh, "w") as f:
            _write_points(f, cloud)
            if cloud.waveforms is not None:
                g = _waveform_group(f, (cloud.info.get("sensor") or {}).get("geiger"))
                first = 0
                for w, t in zip(cloud.waveforms, cloud.starts):
                    _write_block(g, first, w, t)
                    first += len(w)

    write_atomic(path, fill)


#: The ``waveforms`` group's ``units``: a linear receiver's records, a Geiger-mode array's.
RECORD_UNITS = {False: "photoelectrons per sample; starts: s",
                True: "detections per sample over each pulse's shots; starts: s"}


def _waveform_group(f, geiger):
    g = f.create_group("waveforms")
    g.attrs["units"] = RECORD_UNITS[bool(geiger)]
    return g


def _write_block(group, first, waves, starts):
    d = group.create_dataset(f"block_{first:012d}", data=waves, chunks=True)
    d.attrs["first_pulse"] = int(first)
    group.create_dataset(f"starts_{first:012d}", data=starts)


def _write_points(f, cloud):
    d = f.create_dataset("points", data=cloud.points, chunks=True if len(cloud) else None)
    d.attrs["units"] = json.dumps({n: u for n, _, u, _ in POINT_FIELDS})
    d.attrs["meaning"] = json.dumps({n: m for n, _, _, m in POINT_FIELDS})
    f.attrs["info"] = json.dumps(_strict(cloud.info), default=str, allow_nan=False)


def _strict(value):
    """``value`` with numpy's numbers and arrays as Python's (JSON's) numbers and lists and
    its non-finite floats as :data:`NON_FINITE`'s strings (strict JSON)."""
    if isinstance(value, (np.generic, np.ndarray)):
        value = value.tolist()
    if isinstance(value, np.floating):        # a long double's tolist() keeps its type
        value = float(value)
    if isinstance(value, dict):
        return {k: _strict(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_strict(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def _loose(value):
    """:func:`_strict` undone: :data:`NON_FINITE`'s strings as their floats."""
    if isinstance(value, dict):
        return {k: _loose(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_loose(v) for v in value]
    return NON_FINITE.get(value, value) if isinstance(value, str) else value


class WaveformSink:
    """An HDF5 file that a running scan streams its waveforms into, block by block as
    chunks finish (any order, any thread), so that a long scan's records never sit in
    memory; :meth:`finish` adds the points and the parameters and puts the file in place.

    Until then it is written to a temporary beside it, named as every atomic write's
    (:func:`meshladar.io.write_atomic`: ``.meshladar-tmp-<pid>-<8 characters><name>``): a
    scan that fails or is stopped removes it, and one killed outright (SIGKILL, a lost
    machine) leaves it to be removed by the next meshladar write into that folder.

    Parameters
    ----------
    path : str or os.PathLike
        The HDF5 file to make (its folder must exist).
    geiger : bool
        Whether the records are a Geiger-mode array's detections (their ``units``).

    Raises
    ------
    ParameterError
        When ``path`` is not a file name, names a folder, or its folder does not exist.
    OSError
        When the temporary cannot be made, naming ``path``.
    """

    def __init__(self, path, geiger=False):
        h5py = _need("h5py")
        self.path = _not_named_as(_target(path, "waveforms_file"), "HDF5", "waveforms_file")
        fd, self.partial = make_temporary(self.path)
        os.close(fd)                                  # h5py opens it by its name
        try:
            self.file = h5py.File(self.partial, "w")
        except BaseException:
            os.remove(self.partial)
            raise
        self.group = _waveform_group(self.file, geiger)
        self.lock = threading.Lock()

    def write(self, first, waves, starts):
        """Add one block of records.

        Parameters
        ----------
        first : int
            The block's first pulse.
        waves : (k, samples) numpy.ndarray
            Its records.
        starts : (k,) numpy.ndarray
            Their starts, s.
        """
        with self.lock:
            _write_block(self.group, first, waves, starts)

    def finish(self, cloud):
        """Add the points and info, and move the file into place (flushed to disk first).

        Parameters
        ----------
        cloud : PointCloud
            The scan's returns.
        """
        with self.lock:
            _write_points(self.file, cloud)
            self.file.close()
            with open(self.partial, "rb") as fh:
                os.fsync(fh.fileno())
            os.replace(self.partial, self.path)

    def abandon(self):
        """Drop the temporary file (the scan failed or was stopped)."""
        with self.lock:
            self.file.close()
            if os.path.exists(self.partial):
                os.remove(self.partial)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, trace):
        """Drop the temporary where the block failed (the scan, or :meth:`finish`)."""
        if kind is not None:
            self.abandon()
        return False


def read_hdf5(path):
    """Read an HDF5 file that :func:`write_hdf5` (or a scan's ``waveforms_file``) wrote.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    PointCloud
        The records, waveform blocks (if any) and info, exactly as written.

    Raises
    ------
    ParameterError
        When the file is missing, a folder, not HDF5, or has no ``/points``.
    """
    h5py = _need("h5py")
    path = _readable(path, "HDF5")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise _unreadable(path, "HDF5", exc) from None
    with f:
        if "points" not in f:
            raise ParameterError(f"{path}: not a meshladar point cloud (no /points)")
        pts = np.asarray(f["points"][()]).astype(POINT_DTYPE)
        waves = starts = None
        if "waveforms" in f:
            g = f["waveforms"]
            names = sorted((n for n in g if n.startswith("block_")),
                           key=lambda n: int(g[n].attrs["first_pulse"]))
            waves = tuple(np.asarray(g[n][()]) for n in names)
            starts = tuple(np.asarray(g[n.replace("block_", "starts_")][()]) for n in names)
        info = _loose(json.loads(f.attrs.get("info", "{}")))
    return PointCloud(pts, info, waves, starts)
