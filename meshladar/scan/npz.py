"""Point clouds in numpy's ``.npz`` archive (:func:`meshladar.io.save_result`'s result file):
written and read with numpy alone, so a plain install (no laspy, no h5py) saves and loads
a scan, every field and every waveform exactly, without pickle.

The archive holds ``points``, the records as one structured array
(:data:`~meshladar.scan.points.POINT_DTYPE`); where the cloud holds waveforms, for each
block of consecutive pulses ``block_<first pulse, 12 digits>`` (pulses × samples,
photoelectrons per sample) and ``starts_<first pulse>`` (s), as in the HDF5 file (a block
of no pulse is not stored); and its metadata (JSON): ``kind`` ``"points"``, each field's
``units`` and ``meaning``, and the scan's ``info`` (a non-finite number, such as a
Geiger-mode dead time of inf, as the string ``"inf"``, ``"-inf"`` or ``"nan"``, read back
as the float; numpy numbers and arrays as JSON numbers and lists; tuples read back as
lists, as from HDF5).
"""

from __future__ import annotations

import json
import re

from ..errors import ParameterError
from ..io import ResultFileError, load_result, save_result
from .files import _loose, _readable, _strict
from .formats import _not_named_as, _target
from .points import POINT_DTYPE, POINT_FIELDS, PointCloud

__all__ = ["write_npz", "read_npz"]

_BLOCK = re.compile(r"block_(\d{12})")


def write_npz(path, cloud):
    """Write ``cloud`` (records, waveforms if held, info) to an ``.npz`` archive,
    atomically (module docstring).

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
        exist, or ends in .las, .laz, .h5 or .hdf5 (the other writers'), ``cloud`` is not
        a PointCloud, or its ``info`` holds what JSON cannot (other than numpy's numbers
        and arrays).

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from meshladar.scan import POINT_DTYPE, PointCloud, read_npz, write_npz
    >>> cloud = PointCloud(np.zeros(3, POINT_DTYPE), {"dead_time_s": float("inf")})
    >>> path = os.path.join(tempfile.mkdtemp(), "points.npz")
    >>> write_npz(path, cloud)
    >>> back = read_npz(path)
    >>> len(back), back.info["dead_time_s"]
    (3, inf)
    """
    path = _not_named_as(_target(path, "path"), "NPZ")
    if not isinstance(cloud, PointCloud):
        raise ParameterError(f"cloud must be a PointCloud; got {type(cloud).__name__}")
    arrays = {"points": cloud.points}
    if cloud.waveforms is not None:
        first = 0
        for waves, starts in zip(cloud.waveforms, cloud.starts):
            if len(waves):                   # (an empty block's key would be the next's)
                arrays[f"block_{first:012d}"] = waves
                arrays[f"starts_{first:012d}"] = starts
            first += len(waves)
    meta = {"kind": "points", "info": _strict(cloud.info),
            "units": {n: u for n, _, u, _ in POINT_FIELDS},
            "meaning": {n: m for n, _, _, m in POINT_FIELDS}}
    try:
        json.dumps(meta)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"cloud.info must hold what JSON can (numbers, strings, lists, "
                             f"dicts; numpy's numbers and arrays); {exc}") from None
    save_result(path, arrays, meta)


def read_npz(path):
    """Read an ``.npz`` archive that :func:`write_npz` wrote.

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
        When the file is missing, a folder, not an ``.npz`` archive, not a point cloud's (a
        sinogram's result file, say), or damaged (records not one row a return, a block
        without its starts or of another length, a member of another name).
    """
    path = _readable(path, "npz")
    try:
        arrays, meta = load_result(path)
    except ResultFileError as exc:
        raise ParameterError(f"path: {exc}") from None
    if meta.get("kind") != "points" or "points" not in arrays:
        raise ParameterError(f"path: {path!r} is not a meshladar point cloud (its kind: "
                             f"{meta.get('kind', 'none')!r})")
    points = arrays.pop("points")
    if points.dtype != POINT_DTYPE or points.ndim != 1:
        raise ParameterError(f"path: {path!r}: its points are not meshladar's records (one "
                             f"row a return: fields {points.dtype.names}, shape "
                             f"{points.shape})")
    waves, starts = _blocks(path, arrays)
    return PointCloud(points, _loose(meta.get("info", {})), waves, starts)


def _blocks(path, arrays):
    """The archive's waveform blocks and their starts, in pulse order (None, None for
    none), each block checked to be (pulses, samples) with one start a pulse and every
    member named as :func:`write_npz` names them."""
    first = {}
    for key in arrays:
        m = _BLOCK.fullmatch(key)
        if m is None and not (key.startswith("starts_") and "block_" + key[7:] in arrays):
            raise ParameterError(f"path: {path!r} is damaged: member {key!r} is not a "
                                 "waveform block or its starts")
        if m is not None:
            first[key] = int(m.group(1))
    waves, starts = [], []
    for key in sorted(first, key=first.get):
        w, t = arrays[key], arrays.get("starts_" + key[6:])
        if t is None or w.ndim != 2 or t.shape != (len(w),):
            raise ParameterError(f"path: {path!r} is damaged: {key} is not (pulses, "
                                 "samples) with one start a pulse")
        waves.append(w)
        starts.append(t)
    return (tuple(waves), tuple(starts)) if waves else (None, None)
