"""Scan patterns: when each pulse leaves and in which direction, in the sensor's frame.

The sensor's frame: x along the boresight (forward), y to the left, z up; a direction's
azimuth is its angle from x toward y, its elevation its angle above the x–y plane. A
pattern is a :class:`ScanPattern` record of per-pulse arrays; the constructors build the
common scanners from their pulse repetition frequency (``pulse_rate``, pulses per second):

* :func:`raster`: a two-axis raster, rows of elevation swept in azimuth (bidirectional
  when asked);
* :func:`rotating`: a spinning multi-channel head (the Velodyne/Ouster kind), channels at
  fixed elevations fired in turn while the head turns about z;
* :func:`oscillating`: a mirror swinging the beam across track, to ± ``half_angle_deg``
  in a triangle wave (the airborne line scanner);
* :func:`risley`: a Risley prism pair, two wedges turning at different rates, the rose
  pattern of the Livox kind (first-order in the wedges' deviation);
* :func:`flash`: a focal-plane array of ``rows`` × ``columns`` pixels of ``ifov_deg``
  each, every pixel of a frame in the same pulse;
* :func:`ScanPattern` itself: a user's own arrays of times and directions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import check_count, check_flag, check_real, finite_array, readonly_copy
from ..errors import ParameterError

__all__ = ["ScanPattern", "raster", "rotating", "oscillating", "risley", "flash",
           "PATTERNS", "MAX_PULSES"]

#: The most pulses one pattern holds (a 10⁷-pulse scan is ~0.5 GB of records here).
MAX_PULSES = 50_000_000
#: The largest deflection a pattern may point (deg from the boresight's side, below 90).
_MAX_ANGLE_DEG = 180.0


@dataclass(frozen=True)
class ScanPattern:
    """Per-pulse emission times and directions in the sensor's frame (module docstring).

    Parameters
    ----------
    times : (n,) array_like
        Emission time of each pulse, s, non-decreasing.
    directions : (n, 3) array_like
        Each pulse's direction in the sensor's frame (normalised here).
    channels : (n,) array_like of int, optional
        Each pulse's channel (a spinning head's laser) or pixel (a flash array's, row-major);
        default 0.
    scan_angles_deg : (n,) array_like, optional
        The angle a point cloud reports for each pulse (deg; LAS's scan angle); default the
        azimuth.
    kind : str
        The pattern's name, for result files.
    shape : tuple of int, optional
        ``(rows, columns)`` of a flash array (its pixels' grid), else None.
    ifov_deg : float, optional
        A flash array's pixel field of view (deg), else None.

    Raises
    ------
    ParameterError
        When the arrays' lengths differ, a time is not finite or times decrease, a
        direction is zero or not finite, or there are no pulses or more than
        :data:`MAX_PULSES`.
    """

    times: np.ndarray
    directions: np.ndarray
    channels: np.ndarray | None = None
    scan_angles_deg: np.ndarray | None = None
    kind: str = "arrays"
    shape: tuple | None = None
    ifov_deg: float | None = None

    def __post_init__(self):
        t = finite_array("times", self.times).astype(np.float64).ravel()
        n = len(t)
        if not 1 <= n <= MAX_PULSES:
            raise ParameterError(f"times must hold 1 to {MAX_PULSES} pulses; got {n}")
        if np.any(np.diff(t) < 0):
            raise ParameterError("times must be non-decreasing (pulses in emission order)")
        d = finite_array("directions", self.directions).astype(np.float64)
        if d.shape != (n, 3):
            raise ParameterError(f"directions must have shape ({n}, 3), one per time; got "
                                 f"{d.shape}")
        norm = np.linalg.norm(d, axis=1)
        if np.any(norm == 0):
            raise ParameterError("directions must be non-zero")
        d = d / norm[:, None]
        ch = np.zeros(n, np.int32) if self.channels is None else np.asarray(self.channels)
        if ch.shape != (n,) or not np.issubdtype(ch.dtype, np.integer):
            raise ParameterError(f"channels must be {n} integers; got {ch.dtype} of shape "
                                 f"{ch.shape}")
        if self.scan_angles_deg is None:
            angle = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
        else:
            angle = finite_array("scan_angles_deg", self.scan_angles_deg).astype(np.float64)
            if angle.shape != (n,):
                raise ParameterError(f"scan_angles_deg must have shape ({n},); got "
                                     f"{angle.shape}")
        object.__setattr__(self, "times", readonly_copy(t))
        object.__setattr__(self, "directions", readonly_copy(d))
        object.__setattr__(self, "channels", readonly_copy(ch.astype(np.int32)))
        object.__setattr__(self, "scan_angles_deg", readonly_copy(angle))

    def __len__(self):
        return len(self.times)

    @property
    def is_flash(self) -> bool:
        """Whether it is a flash array (pixels of a frame share one pulse)."""
        return self.shape is not None

    def describe(self) -> dict:
        """The pattern's summary, with units in the names (for result files).

        Returns
        -------
        dict
            ``kind``, ``pulses``, ``duration_s``, ``channels`` (and a flash array's
            ``rows``, ``columns``, ``ifov_deg``).
        """
        out = {"kind": self.kind, "pulses": len(self), "duration_s": float(self.times[-1]
                                                                           - self.times[0]),
               "channels": int(self.channels.max()) + 1}
        if self.is_flash:
            out.update(rows=self.shape[0], columns=self.shape[1], ifov_deg=self.ifov_deg)
        return out


def _direction(azimuth, elevation):
    """Unit vectors at azimuth (from x toward y) and elevation (above x–y), radians."""
    ce = np.cos(elevation)
    return np.stack([ce * np.cos(azimuth), ce * np.sin(azimuth), np.sin(elevation)], axis=1)


def _times(pulse_rate, n, name="pulse_rate"):
    rate = check_real(name, pulse_rate, low=0.0, low_open=True, high=1e12)
    if n > MAX_PULSES:
        raise ParameterError(f"the pattern would hold {n} pulses, above {MAX_PULSES}: "
                             "shorten duration or lower pulse_rate")
    return np.arange(n) / rate


def _angles(name, value):
    a = finite_array(name, value).astype(np.float64)
    if a.ndim > 1:
        raise ParameterError(f"{name} must be one angle or a 1-D array of them; got shape "
                             f"{a.shape}")
    a = a.ravel()
    if a.size == 0:
        raise ParameterError(f"{name} must be 1 or more angles in [-180, 180] deg; got none")
    outside = np.flatnonzero(np.abs(a) > _MAX_ANGLE_DEG)
    if outside.size:
        raise ParameterError(f"{name} must be 1 or more angles in [-180, 180] deg; got "
                             f"{a[outside[0]]:g} (value {outside[0]} of {a.size})")
    return a


def _count(duration, rate):
    dur = check_real("duration", duration, low=0.0, low_open=True, high=1e6)
    r = check_real("pulse_rate", rate, low=0.0, low_open=True, high=1e12)
    return max(1, int(math.floor(dur * r + 1e-9)))


def raster(azimuth_deg, elevation_deg, *, pulse_rate, bidirectional=False):
    """A two-axis raster: one row of pulses per elevation, swept across the azimuths.

    Parameters
    ----------
    azimuth_deg, elevation_deg : array_like
        The azimuths of a row and the rows' elevations (deg, in [-180, 180]).
    pulse_rate : float
        Pulses per second (> 0).
    bidirectional : bool
        Sweep every other row backwards (a mirror's return stroke), default False.

    Returns
    -------
    ScanPattern
        Rows in order of ``elevation_deg``; channel 0; scan angle the azimuth.
    """
    az, el = np.radians(_angles("azimuth_deg", azimuth_deg)), np.radians(
        _angles("elevation_deg", elevation_deg))
    bidirectional = check_flag("bidirectional", bidirectional)
    rows = np.repeat(el, len(az))
    cols = np.tile(az, len(el)).reshape(len(el), len(az))
    if bidirectional:
        cols[1::2] = cols[1::2, ::-1]
    cols = cols.ravel()
    return ScanPattern(_times(pulse_rate, len(rows)), _direction(cols, rows),
                       kind="raster", scan_angles_deg=np.degrees(cols))


def rotating(elevations_deg, *, rotation_hz, pulse_rate, duration):
    """A spinning multi-channel head: its channels, at fixed elevations, fire in turn
    (pulse k is channel k mod channels) while the head turns about z at ``rotation_hz``.

    Parameters
    ----------
    elevations_deg : array_like
        Each channel's elevation (deg), e.g. ``np.linspace(-15, 15, 32)``.
    rotation_hz : float
        Turns per second (> 0; azimuth 2π f t, counter-clockwise seen from +z).
    pulse_rate : float
        Pulses per second over all channels (> 0).
    duration : float
        Seconds of scanning (> 0).

    Returns
    -------
    ScanPattern
        Channel = the laser's index; scan angle the head's azimuth in [-180, 180).
    """
    el = np.radians(_angles("elevations_deg", elevations_deg))
    f = check_real("rotation_hz", rotation_hz, low=0.0, low_open=True, high=1e6)
    n = _count(duration, pulse_rate)
    t = _times(pulse_rate, n)
    ch = (np.arange(n) % len(el)).astype(np.int32)
    az = np.mod(2 * np.pi * f * t + np.pi, 2 * np.pi) - np.pi
    return ScanPattern(t, _direction(az, el[ch]), channels=ch, kind="rotating",
                       scan_angles_deg=np.degrees(az))


def oscillating(half_angle_deg, *, scan_hz, pulse_rate, duration):
    """A mirror swinging the beam across track (about x, toward ±y) in a triangle wave of
    amplitude ``half_angle_deg`` and ``scan_hz`` full swings per second.

    Parameters
    ----------
    half_angle_deg : float
        Largest deflection from the boresight (deg, in (0, 90)).
    scan_hz : float
        Full swings (out and back) per second (> 0).
    pulse_rate, duration : float
        Pulses per second and seconds of scanning (> 0).

    Returns
    -------
    ScanPattern
        Scan angle = the deflection toward +y (deg).
    """
    a = check_real("half_angle_deg", half_angle_deg, low=0.0, low_open=True, high=90.0,
                   high_open=True)
    f = check_real("scan_hz", scan_hz, low=0.0, low_open=True, high=1e6)
    t = _times(pulse_rate, _count(duration, pulse_rate))
    # a triangle wave: 0 → +a → −a → 0 over each swing
    angle = np.radians(a) * (1.0 - 4.0 * np.abs(np.mod(f * t + 0.25, 1.0) - 0.5))
    return ScanPattern(t, _direction(angle, np.zeros_like(angle)), kind="oscillating",
                       scan_angles_deg=np.degrees(angle))


def risley(deviation_deg, *, prism_hz, pulse_rate, duration):
    """A Risley prism pair: two wedges each deviating the beam by ``deviation_deg``, turning
    at ``prism_hz = (f1, f2)`` turns per second (opposite signs for the rose pattern); the
    deflection is the sum of the two wedges' (first order in the deviation).

    Parameters
    ----------
    deviation_deg : float or (2,) array_like
        Each wedge's deviation (deg, in (0, 45)).
    prism_hz : (2,) array_like
        The wedges' turns per second (non-zero, finite; e.g. ``(100.0, -70.0)``).
    pulse_rate, duration : float
        Pulses per second and seconds of scanning (> 0).

    Returns
    -------
    ScanPattern
        Scan angle = the deflection's azimuth about the boresight (deg).
    """
    dev = np.broadcast_to(finite_array("deviation_deg", deviation_deg), (2,)).astype(float)
    if np.any(dev <= 0) or np.any(dev >= 45):
        raise ParameterError(f"deviation_deg must be in (0, 45) deg; got {dev.tolist()}")
    f = finite_array("prism_hz", prism_hz).astype(float)
    if f.shape != (2,) or np.any(f == 0):
        raise ParameterError(f"prism_hz must be two non-zero rates (Hz); got {f.tolist()}")
    t = _times(pulse_rate, _count(duration, pulse_rate))
    dy = sum(np.radians(dev[i]) * np.cos(2 * np.pi * f[i] * t) for i in range(2))
    dz = sum(np.radians(dev[i]) * np.sin(2 * np.pi * f[i] * t) for i in range(2))
    d = np.stack([np.ones_like(t), np.tan(dy), np.tan(dz)], axis=1)
    return ScanPattern(t, d, kind="risley", scan_angles_deg=np.degrees(np.arctan2(dz, dy)))


def flash(rows, columns, *, ifov_deg, frame_rate=1.0, frames=1):
    """A flash focal-plane array: ``rows`` × ``columns`` pixels, each seeing ``ifov_deg`` ×
    ``ifov_deg``; one pulse lights the whole field each frame.

    Pixel (i, j) (row i from the top, column j from the left, seen along the boresight)
    looks along (1, (c − j)·p, (r − i)·p) with p = tan(ifov), c = (columns − 1)/2 and
    r = (rows − 1)/2: pixels evenly spaced on the focal plane, row 0 the highest, column 0
    the leftmost (+y). Its channel is i·columns + j.

    Parameters
    ----------
    rows, columns : int
        The array's size (≥ 1 each).
    ifov_deg : float
        A pixel's field of view (deg, in (0, 10]).
    frame_rate : float
        Frames per second (> 0), default 1.
    frames : int
        Number of frames (≥ 1), default 1.

    Returns
    -------
    ScanPattern
        One record per pixel and frame, frame by frame, each frame's pixels row-major.
    """
    r, c = check_count("rows", rows), check_count("columns", columns)
    ifov = check_real("ifov_deg", ifov_deg, low=0.0, low_open=True, high=10.0)
    k = check_count("frames", frames)
    if r * c * k > MAX_PULSES:
        raise ParameterError(f"{r}x{c} pixels over {k} frames is above {MAX_PULSES} records")
    i, j = np.divmod(np.arange(r * c), c)
    pitch = math.tan(math.radians(ifov))        # pixels evenly spaced on the focal plane
    d = np.stack([np.ones(r * c), ((c - 1) / 2 - j) * pitch, ((r - 1) / 2 - i) * pitch], axis=1)
    az = np.arctan2(d[:, 1], 1.0)
    t = np.repeat(_times(frame_rate, k, "frame_rate"), r * c)
    return ScanPattern(t, np.tile(d, (k, 1)), channels=np.tile(i * c + j, k).astype(np.int32),
                       scan_angles_deg=np.tile(np.degrees(az), k), kind="flash", shape=(r, c),
                       ifov_deg=ifov)


#: The built-in patterns by name (the CLI's ``--pattern KIND ...``).
PATTERNS = {"raster": raster, "rotating": rotating, "oscillating": oscillating,
            "risley": risley, "flash": flash}
