"""A LAS file of another tool (a real scanner's, HELIOS++'s) as a :class:`PointCloud`, so
that it can be drawn over a scene (:func:`meshladar.scan.read_las` with ``foreign=True``,
``meshladar view --points``): LAS's own fields only."""

from __future__ import annotations

import os

import numpy as np

from .points import POINT_DTYPE, PointCloud

__all__ = ["FOREIGN_FIELDS", "LAS_SCAN_ANGLE_STEP", "foreign_points"]

#: The fields a LAS file of any tool gives (``emission_time``: its GPS time, where its point
#: format has one); the others are NaN, or -1 for the truth's part and face.
FOREIGN_FIELDS = ("x", "y", "z", "intensity", "return_number", "number_of_returns",
                  "pulse_id", "scan_angle", "emission_time")
#: LAS 1.4's scan-angle step for point formats 6-10 (degrees; earlier formats count
#: degrees), for reading and writing alike.
LAS_SCAN_ANGLE_STEP = 0.006


def foreign_points(las, path):
    """``las`` (laspy's LasData) as a PointCloud of :data:`FOREIGN_FIELDS`.

    Parameters
    ----------
    las : laspy.LasData
    path : str
        Its file, for ``info``.

    Returns
    -------
    PointCloud
        ``intensity`` is LAS's (the tool's own units, not photoelectrons), ``pulse_id`` the
        point's index; ``info``: ``file``, ``foreign`` True, ``fields`` (those it holds)
        and ``intensity_units`` ``"LAS intensity"``.
    """
    pts = np.zeros(len(las.points), POINT_DTYPE)
    for name in POINT_DTYPE.names:
        pts[name] = -1 if name in ("true_part", "true_face") else np.nan \
            if POINT_DTYPE[name].kind == "f" else 0
    pts["x"], pts["y"], pts["z"] = np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)
    pts["intensity"] = np.asarray(las.intensity)
    pts["return_number"] = np.asarray(las.return_number)
    pts["number_of_returns"] = np.asarray(las.number_of_returns)
    pts["pulse_id"] = np.arange(len(pts))
    fields = list(FOREIGN_FIELDS)
    if las.point_format.id >= 6:
        pts["scan_angle"] = np.asarray(las.scan_angle) * LAS_SCAN_ANGLE_STEP
    else:
        pts["scan_angle"] = np.asarray(las.scan_angle_rank)
    if "gps_time" in las.point_format.dimension_names:
        pts["emission_time"] = np.asarray(las.gps_time)
    else:
        fields.remove("emission_time")
    return PointCloud(pts, {"file": os.fspath(path), "foreign": True, "fields": fields,
                            "intensity_units": "LAS intensity"})
