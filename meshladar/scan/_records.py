"""A chunk's point records in one compiled pass (:func:`meshladar.scan.run.scan`'s chunks):
each return's measured position, range and time, its echo's fields, its pulse's, and its
ground truth (:func:`._kernels.assign_truth`), written into the
:data:`~meshladar.scan.points.POINT_DTYPE` records field by field as numpy would (the same
conversions), without the per-field arrays and passes."""

from __future__ import annotations

import numba
import numpy as np

from ._kernels import assign_truth

__all__ = ["fill_records"]


@numba.njit(cache=True, nogil=True)
def fill_records(rec, ret, pulse_of, optics, hits, part_of):   # pragma: no cover - compiled
    """rec[i] for return i (sorted by pulse): ``ret`` = (pulse, time, amplitude, width,
    intensity, return_number, number_of_returns, reach: the most a sub-ray's echo time may
    lie from the return's for its truth, s); ``pulse_of`` = (first pulse id, emission
    times, scan angles, channels, each pulse's further reach for an early return, s:
    :func:`._kernels.assign_truth`), per pulse of the chunk; ``optics`` = (origins, axes,
    c/2): the point is origin + (c/2 · time) · axis; ``hits`` = (tau, pe, distance,
    points, face, shift) of the sub-rays for the truth; ``part_of`` each face's part."""
    pulse, time, amplitude, width, intensity, number, count, reach = ret
    first_id, emitted, angles, channels, walk = pulse_of
    origins, axes, half_c = optics
    tau, pe, distance, points, face, shift = hits
    n, n_ret = tau.shape[0], pulse.shape[0]
    first = np.zeros(n, np.int64)                 # each pulse's first return, and how many
    many = np.zeros(n, np.int64)
    for i in range(n_ret - 1, -1, -1):
        first[pulse[i]] = i
        many[pulse[i]] += 1
    true_range, xyz = np.zeros(n_ret), np.zeros((n_ret, 3))
    true_face, doppler = np.full(n_ret, -1, np.int64), np.zeros(n_ret)
    assign_truth(first, many, time, (reach, walk), tau, pe, distance, points, face, shift, true_range, xyz,
                 true_face, doppler)
    for i in range(n_ret):
        p = pulse[i]
        r = half_c * time[i]
        rec[i].x = origins[p, 0] + r * axes[p, 0]
        rec[i].y = origins[p, 1] + r * axes[p, 1]
        rec[i].z = origins[p, 2] + r * axes[p, 2]
        rec[i].range = r
        rec[i].time = time[i]
        rec[i].amplitude = amplitude[i]
        rec[i].width = width[i]
        rec[i].intensity = intensity[i]
        rec[i].return_number = number[i]
        rec[i].number_of_returns = count[i]
        rec[i].pulse_id = first_id + p
        rec[i].emission_time = emitted[p]
        rec[i].scan_angle = angles[p]
        rec[i].channel = channels[p]
        rec[i].doppler = doppler[i]
        f = true_face[i]
        rec[i].true_part = part_of[f] if f >= 0 else -1
        rec[i].true_face = f
        rec[i].true_range = true_range[i]
        rec[i].true_x = xyz[i, 0]
        rec[i].true_y = xyz[i, 1]
        rec[i].true_z = xyz[i, 2]
