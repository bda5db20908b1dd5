"""The point cloud a scan records: one numpy record per return, with its ground truth.

Fields (:data:`POINT_FIELDS`: name, dtype, unit, meaning):
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._validate import check_count
from ..errors import ParameterError

__all__ = ["POINT_FIELDS", "POINT_DTYPE", "PointCloud", "CONVENTIONS"]

#: Every field of a return: (name, dtype, unit, meaning).
POINT_FIELDS = (
    ("x", "f8", "m", "measured position, world frame"),
    ("y", "f8", "m", "measured position, world frame"),
    ("z", "f8", "m", "measured position, world frame"),
    ("range", "f8", "m", "measured one-way range from the sensor, c t / 2"),
    ("time", "f8", "s", "two-way time of the echo after its pulse's emission"),
    ("amplitude", "f4", "photoelectrons", "the echo's peak, per sample"),
    ("width", "f4", "s", "the echo's full width at half maximum"),
    ("intensity", "f4", "photoelectrons", "the echo's photoelectrons (area under its fit)"),
    ("return_number", "u1", "", "1 for the first echo of its pulse in time"),
    ("number_of_returns", "u1", "", "echoes found for its pulse"),
    ("pulse_id", "u8", "", "the pulse's index in the scan pattern"),
    ("emission_time", "f8", "s", "when the pulse left, the pattern's clock"),
    ("scan_angle", "f4", "deg", "the pattern's scan angle of the pulse"),
    ("channel", "i4", "", "the channel (laser) or pixel (row-major) of the pulse"),
    ("doppler", "f4", "Hz", "the echo's sub-rays' photoelectron-weighted Doppler shift, "
                            "positive closing"),
    ("true_part", "i4", "", "the scene part of the echo's strongest sub-ray (-1: noise)"),
    ("true_face", "i8", "", "its face, numbered part by part (-1: noise)"),
    ("true_range", "f8", "m", "the echo's sub-rays' photoelectron-weighted distance"),
    ("true_x", "f8", "m", "their photoelectron-weighted hit point, world frame"),
    ("true_y", "f8", "m", "their photoelectron-weighted hit point, world frame"),
    ("true_z", "f8", "m", "their photoelectron-weighted hit point, world frame"),
)
__doc__ += "\n".join(f"\n* ``{n}`` ({u or 'count'}): {m}" for n, _, u, m in POINT_FIELDS)

#: The records' dtype.
POINT_DTYPE = np.dtype([(n, t) for n, t, _, _ in POINT_FIELDS])

#: What every scan records about its physics.
CONVENTIONS = {"radiometry": "power", "mode": "monostatic", "normals": "flat, two-sided",
               "bounces": 1, "units": "photoelectrons", "frame": "world (the scene's)"}


@dataclass(frozen=True)
class PointCloud:
    """A scan's returns (:data:`POINT_DTYPE` records) and how they were made.

    Attributes
    ----------
    points : numpy.ndarray
        One record per return, in pulse order, then time.
    info : dict
        The pattern, platform and sensor (``describe()``), the conventions
        (:data:`CONVENTIONS`) and the seed.
    waveforms : tuple of numpy.ndarray, optional
        The pulses' records when asked for, in blocks of consecutive pulses (one per chunk
        of the scan, each (pulses, samples): a block's records share a length): measured
        photoelectrons per sample (a Geiger-mode scan's: detections per sample over its
        shots); else None.
    starts : tuple of numpy.ndarray, optional
        Each record's start after its pulse's emission, s, block by block.
    """

    points: np.ndarray
    info: dict = field(default_factory=dict)
    waveforms: tuple | None = None
    starts: tuple | None = None

    def __len__(self):
        return len(self.points)

    def waveform(self, pulse_id):
        """One pulse's record and its start: ``(samples, start_s)``.

        Parameters
        ----------
        pulse_id : int
            The pulse's index in the scan pattern.

        Returns
        -------
        tuple
            ``(numpy.ndarray, float)``: the record (per sample) and its start after the
            pulse's emission (s).
        """
        if self.waveforms is None:
            raise ParameterError("this cloud holds no waveforms: scan(..., "
                                 "keep_waveforms=True)")
        k = int(pulse_id)
        for block, start in zip(self.waveforms, self.starts):
            if 0 <= k < len(block):
                return block[k], float(start[k])
            k -= len(block)
        raise ParameterError(f"pulse_id must be in [0, {sum(map(len, self.starts))}); got "
                             f"{pulse_id!r}")

    @property
    def xyz(self) -> np.ndarray:
        """Measured positions (n, 3)."""
        return np.stack([self.points["x"], self.points["y"], self.points["z"]], axis=1)

    @property
    def true_xyz(self) -> np.ndarray:
        """True positions (n, 3) (nan for noise returns)."""
        return np.stack([self.points["true_x"], self.points["true_y"], self.points["true_z"]],
                        axis=1)

    def image(self, field="range", frame=0, return_number=1):
        """A flash frame's image of one field: (rows, columns), nan where that pixel has no
        such return (a flash scan's cloud only).

        Parameters
        ----------
        field : str
            A record field (:data:`POINT_FIELDS`), e.g. ``"range"`` or ``"intensity"``.
        frame : int
            The frame, 0-based: in [0, frames) (no negative index, as :meth:`waveform`'s
            ``pulse_id``).
        return_number : int
            Which of each pixel's returns (1: the first in time), in [1, 15].

        Returns
        -------
        (rows, columns) numpy.ndarray
            float64; row 0 the top of the field, column 0 its left (+y).

        Raises
        ------
        ParameterError
            When the cloud is not a flash scan's, ``field`` is not a record field, or
            ``frame`` or ``return_number`` is out of its range.
        """
        pattern = self.info.get("pattern", {})
        if pattern.get("kind") != "flash":
            raise ParameterError("image() needs a flash scan's cloud (pattern kind 'flash'); "
                                 f"this one's is {pattern.get('kind')!r}")
        if field not in POINT_DTYPE.names:
            raise ParameterError(f"field must be one of {POINT_DTYPE.names}; got {field!r}")
        rows, cols = pattern["rows"], pattern["columns"]
        frames = max(pattern["pulses"] // (rows * cols), 1)
        if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)) or \
                not 0 <= frame < frames:
            raise ParameterError(f"frame must be an integer in [0, {frames - 1}] (the "
                                 f"cloud's {frames} frames, 0-based); got {frame!r}")
        check_count("return_number", return_number, high=15)
        pts = self.points
        sel = ((pts["pulse_id"] // (rows * cols) == frame)
               & (pts["return_number"] == return_number))
        out = np.full(rows * cols, np.nan)
        out[pts["channel"][sel]] = pts[field][sel]
        return out.reshape(rows, cols)

    @property
    def range_error(self) -> np.ndarray:
        """Measured minus true range (m; nan for noise returns)."""
        return self.points["range"] - self.points["true_range"]
