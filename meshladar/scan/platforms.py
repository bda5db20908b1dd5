"""Platforms: the sensor's pose (position and attitude) against time.

Frames (ROS REP 103's): the world's axes are the scene's; the platform's body frame has x
forward, y left, z up. An attitude is (roll, pitch, yaw) in degrees, applied as
``scipy.spatial.transform.Rotation.from_euler("ZYX", [yaw, pitch, roll], degrees=True)``:
yaw about z, then pitch about the new y, then roll about the new x; it maps body vectors to
world vectors. With z up and y left a positive pitch turns the nose down: pitch 90° points
the body's x straight down (a nadir-looking sensor).

The sensor sits on the platform at ``mount_offset`` (body frame, scene units) and its own
frame (:mod:`.patterns`: x the boresight) is turned from the body's by ``boresight_deg``,
another (roll, pitch, yaw). Every pulse is cast from the sensor's pose at its own emission
time.

Kinds: :meth:`Platform.static`, :meth:`Platform.moving` (constant velocity, at any time),
:meth:`Platform.waypoints` (positions interpolated linearly or by a cubic spline,
attitudes by spherical linear interpolation) and :meth:`Platform.from_csv` (a trajectory
file with the columns ``time, x, y, z, roll, pitch, yaw``: seconds, scene units, degrees in
the convention above, one header line, comma-separated). Waypoints hold a pose only
between their first and last times: a scan refuses a pattern whose pulses leave outside
them (:meth:`Platform.check_covers`); a trajectory in GPS time reads with ``time_offset``,
its time at the pattern's t = 0.
"""

from __future__ import annotations

import csv
import math
import functools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, Slerp

from .._validate import check_choice, check_path, check_real, finite_array, readonly_copy
from ..errors import ParameterError

__all__ = ["Platform", "INTERPOLATIONS", "TRAJECTORY_COLUMNS"]

#: How waypoints' positions are interpolated.
INTERPOLATIONS = ("linear", "spline")
#: The columns of a trajectory file, in order.
TRAJECTORY_COLUMNS = ("time", "x", "y", "z", "roll", "pitch", "yaw")
#: How far beyond its waypoints' ends a time still counts as covered, s: the rounding of a
#: GPS time less its offset (~1e-10 s), not a pose anyone could tell from the end's.
_TIME_SLACK = 1e-9
#: The half-step of the sensor velocity's difference, s.
_VELOCITY_STEP = 1e-6


#: The largest angle an attitude or boresight takes, degrees (angles wrap; beyond this
#: a float64 angle keeps less than 1e-6 degree of precision).
MAX_ANGLE_DEG = 1e9


def _triple(name, value, shape=(3,)):
    a = finite_array(name, value).astype(np.float64)
    if a.shape != shape:
        raise ParameterError(f"{name} must have shape {shape}; got {a.shape}")
    if name.endswith("_deg") and np.any(np.abs(a) > MAX_ANGLE_DEG):
        raise ParameterError(f"{name} must be angles within ±{MAX_ANGLE_DEG:g} degrees "
                             f"(they wrap; larger ones lose their precision); got "
                             f"{float(a[np.abs(a) > MAX_ANGLE_DEG][0])!r}")
    return a


def _row(path, line, values):
    """One trajectory row's 7 numbers (``line``: its line in the file, 1-based)."""
    if len(values) != len(TRAJECTORY_COLUMNS):
        raise ParameterError(f"{path}, line {line}: a row holds {len(TRAJECTORY_COLUMNS)} "
                             f"values ({','.join(TRAJECTORY_COLUMNS)}); got {len(values)}")
    try:
        row = [float(x) for x in values]
    except ValueError as exc:
        raise ParameterError(f"{path}, line {line}: every value must be a number "
                             f"({exc})") from None
    for name, x in zip(TRAJECTORY_COLUMNS, row):
        if not math.isfinite(x):
            raise ParameterError(f"{path}, line {line}: {name} is {x}; every value must be a "
                                 "finite number")
    return row


def rotation(attitude_deg):
    """The body-to-world rotation of (roll, pitch, yaw) in degrees, (n, 3) or (3,)."""
    a = np.asarray(attitude_deg, np.float64)
    return Rotation.from_euler("ZYX", a[..., ::-1], degrees=True)


@dataclass(frozen=True)
class Platform:
    """A sensor's carrier: waypoints of position and attitude against time (module
    docstring). Build it with :meth:`static`, :meth:`moving`, :meth:`waypoints` or
    :meth:`from_csv`.

    Parameters
    ----------
    times : (k,) array_like
        Waypoint times, s, increasing (one waypoint: a static platform).
    positions : (k, 3) array_like
        Positions, scene units.
    attitudes_deg : (k, 3) array_like
        (roll, pitch, yaw) at each waypoint, deg.
    interpolation : str
        ``"linear"`` (default) or ``"spline"`` (a cubic spline with natural ends; needs
        ≥ 3 waypoints) for the positions; attitudes always by slerp.
    mount_offset : (3,) array_like
        The sensor's position on the platform, body frame, scene units (default 0).
    boresight_deg : (3,) array_like
        The sensor frame's (roll, pitch, yaw) in the body frame, deg (default 0).
    extrapolate : bool
        Two waypoints' constant velocity holds at every time (:meth:`moving`'s); default
        False: the poses are the waypoints' between their first and last times only.
    time_origin : float
        The clock's time at the pattern's t = 0, s (default 0; a trajectory file's
        ``time_offset``): LAS files take a return's GPS time as it plus its emission
        time, and ``describe`` records it.

    Raises
    ------
    ParameterError
        When the arrays' shapes disagree, a value is not finite, the times do not increase,
        ``interpolation`` is unknown, or ``extrapolate`` is given to other than two
        waypoints interpolated linearly.
    """

    times: np.ndarray
    positions: np.ndarray
    attitudes_deg: np.ndarray
    interpolation: str = "linear"
    mount_offset: tuple = (0.0, 0.0, 0.0)
    boresight_deg: tuple = (0.0, 0.0, 0.0)
    extrapolate: bool = False
    time_origin: float = 0.0

    def __post_init__(self):
        t = finite_array("times", self.times).astype(np.float64).ravel()
        k = len(t)
        if k == 0 or np.any(np.diff(t) <= 0):
            raise ParameterError(f"times must be 1 or more increasing waypoint times; got {k} "
                                 "values" + (" not increasing" if k else ""))
        pos = _triple("positions", self.positions, (k, 3))
        att = _triple("attitudes_deg", self.attitudes_deg, (k, 3))
        check_choice("interpolation", self.interpolation, INTERPOLATIONS)
        if self.interpolation == "spline" and k < 3:
            raise ParameterError(f"interpolation='spline' needs 3 or more waypoints; got {k}")
        if not isinstance(self.extrapolate, bool):
            raise ParameterError(f"extrapolate must be True or False; got {self.extrapolate!r}")
        if self.extrapolate and (k != 2 or self.interpolation != "linear"):
            raise ParameterError("extrapolate=True is a constant velocity: it needs 2 "
                                 f"waypoints interpolated linearly; got {k}, "
                                 f"{self.interpolation!r}")
        object.__setattr__(self, "time_origin", check_real("time_origin", self.time_origin))
        object.__setattr__(self, "times", readonly_copy(t))
        object.__setattr__(self, "positions", readonly_copy(pos))
        object.__setattr__(self, "attitudes_deg", readonly_copy(att))
        object.__setattr__(self, "mount_offset",
                           tuple(_triple("mount_offset", self.mount_offset).tolist()))
        object.__setattr__(self, "boresight_deg",
                           tuple(_triple("boresight_deg", self.boresight_deg).tolist()))

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def static(cls, position, attitude_deg=(0.0, 0.0, 0.0), **mount):
        """A platform at rest.

        Parameters
        ----------
        position : (3,) array_like
            Where it is.
        attitude_deg : (3,) array_like
            (roll, pitch, yaw), deg.
        **mount
            ``mount_offset`` and ``boresight_deg``.

        Returns
        -------
        Platform
        """
        return cls([0.0], [_triple("position", position)], [_triple("attitude_deg", attitude_deg)],
                   **mount)

    @classmethod
    def moving(cls, position, velocity, attitude_deg=(0.0, 0.0, 0.0), **mount):
        """A platform moving at constant velocity with a fixed attitude.

        Parameters
        ----------
        position : (3,) array_like
            Where it is at t = 0.
        velocity : (3,) array_like
            Scene units per second.
        attitude_deg : (3,) array_like
            (roll, pitch, yaw), deg.
        **mount
            ``mount_offset`` and ``boresight_deg``.

        Returns
        -------
        Platform
        """
        p0, v = _triple("position", position), _triple("velocity", velocity)
        return cls([0.0, 1.0], [p0, p0 + v], [attitude_deg, attitude_deg], extrapolate=True,
                   **mount)

    @classmethod
    def waypoints(cls, times, positions, attitudes_deg, interpolation="linear", **mount):
        """Waypoints interpolated between (linearly or by spline). They cover their first
        to last time: :func:`~meshladar.scan.scan` refuses pulses outside it
        (:meth:`check_covers`; :meth:`sensor_poses` holds the first or last pose there).

        Parameters
        ----------
        times, positions, attitudes_deg, interpolation
            As the class's.
        **mount
            ``mount_offset`` and ``boresight_deg``.

        Returns
        -------
        Platform
        """
        return cls(times, positions, attitudes_deg, interpolation, **mount)

    @classmethod
    def from_csv(cls, path, interpolation="linear", time_offset=0.0, **mount):
        """A trajectory file: a header line, then rows of ``time, x, y, z, roll, pitch,
        yaw`` (:data:`TRAJECTORY_COLUMNS`; s, scene units, deg; UTF-8, a byte-order mark
        allowed).

        Parameters
        ----------
        path : str or os.PathLike
            The CSV file.
        interpolation : str
            ``"linear"`` or ``"spline"``.
        time_offset : float
            The file's time at the pattern's t = 0, s (default 0): the platform's times
            are the file's less it (a trajectory in GPS seconds of week, its scan's start),
            and its ``time_origin``.
        **mount
            ``mount_offset`` and ``boresight_deg``.

        Returns
        -------
        Platform

        Raises
        ------
        ParameterError
            When the file cannot be read, its header differs, a row does not hold 7
            values (its line named), a value is not a number, or it holds fewer than two
            rows (one pose covers no span of time: :meth:`static` is a platform at rest).
        """
        path = check_path("path", path)
        offset = check_real("time_offset", time_offset)
        try:
            with open(path, newline="", encoding="utf-8-sig") as f:
                rows = list(csv.reader(f))
        except (OSError, UnicodeDecodeError) as exc:
            raise ParameterError(f"path: cannot read the trajectory {path!r} ({exc})") from None
        header = [h.strip().lower() for h in rows[0]] if rows else []
        if tuple(header) != TRAJECTORY_COLUMNS:
            raise ParameterError(f"{path}: the header must be {','.join(TRAJECTORY_COLUMNS)}; "
                                 f"got {','.join(header) or 'nothing'}")
        lines = [line for line, r in enumerate(rows[1:], 2) if r]
        data = np.array([_row(path, line, rows[line - 1]) for line in lines],
                        np.float64).reshape(-1, len(TRAJECTORY_COLUMNS))
        back = np.flatnonzero(np.diff(data[:, 0]) <= 0)
        if back.size:
            a, b = int(back[0]), int(back[0]) + 1
            raise ParameterError(f"{path}, line {lines[b]}: time {float(data[b, 0])!r} does "
                                 f"not follow line {lines[a]}'s {float(data[a, 0])!r}; the "
                                 "times must increase")
        if len(data) < 2:
            raise ParameterError(f"{path}: a trajectory needs 2 or more rows (its poses cover "
                                 f"their first to last time); got {len(data)} (a platform "
                                 "at rest: Platform.static)")
        return cls(data[:, 0] - offset, data[:, 1:4], data[:, 4:7], interpolation,
                   time_origin=offset, **mount)

    # -- poses -------------------------------------------------------------------------
    @functools.cached_property
    def is_static(self) -> bool:
        """Whether the platform never moves (one position and one attitude throughout;
        found once, the platform being immutable)."""
        return bool(np.all(self.positions == self.positions[0])
                    and np.all(self.attitudes_deg == self.attitudes_deg[0]))

    def _positions(self, t):
        """Body positions (n, 3) at times t (two or more waypoints)."""
        if self.interpolation == "spline":
            return CubicSpline(self.times, self.positions, bc_type="natural")(
                np.clip(t, self.times[0], self.times[-1]))
        if self.extrapolate:         # constant velocity, extrapolated both ways
            v = (self.positions[1] - self.positions[0]) / (self.times[1] - self.times[0])
            return self.positions[0] + (t - self.times[0])[:, None] * v
        return np.stack([np.interp(t, self.times, self.positions[:, i]) for i in range(3)],
                        axis=1)

    def _body(self, t):
        """Body positions (n, 3) and rotations at times t."""
        k = len(self.times)
        if k == 1:
            return (np.broadcast_to(self.positions[0], (len(t), 3)).copy(),
                    rotation(np.broadcast_to(self.attitudes_deg[0], (len(t), 3))))
        pos = self._positions(t)
        slerp = Slerp(self.times, rotation(self.attitudes_deg))
        return pos, slerp(np.clip(t, self.times[0], self.times[-1]))

    @functools.cached_property
    def _one_attitude(self):
        """(sensor-to-world matrix, the mount offset in the world frame) of a platform of
        one attitude, made once (scipy's rotations, per chunk of a scan, held the GIL its
        other threads wait for); None when the attitude changes."""
        if not np.all(self.attitudes_deg == self.attitudes_deg[0]):
            return None
        rot = rotation(self.attitudes_deg[0])
        mats = (rot * rotation(np.asarray(self.boresight_deg))).as_matrix()
        return mats, rot.apply(np.asarray(self.mount_offset))

    def check_covers(self, t, name="pattern"):
        """Refuse times outside the waypoints' first to last, to 1 ns (a static or
        constant-velocity platform covers every time).

        Parameters
        ----------
        t : array_like
            Times, s (the pattern's emission times).
        name : str
            What the times are, for the message.

        Raises
        ------
        ParameterError
            Naming both spans, when a time lies outside the waypoints'.
        """
        t = np.asarray(t, np.float64)
        if len(self.times) == 1 or self.extrapolate or not t.size:
            return
        lo, hi = float(t.min()), float(t.max())
        first, last = float(self.times[0]), float(self.times[-1])
        if lo < first - _TIME_SLACK or hi > last + _TIME_SLACK:
            raise ParameterError(
                f"platform: the {name}'s pulses leave from {lo:.9g} s to {hi:.9g} s, outside "
                f"the platform's waypoints, from {first:.9g} s to {last:.9g} s: they must "
                "cover the scan (a GPS-time file: Platform.from_csv(path, time_offset=its "
                "time at the pattern's t = 0), on the command line 'FILE.csv "
                "time_offset=SECONDS')")

    def sensor_poses(self, t):
        """The sensor's pose at times ``t``: the body's pose, the mount offset and the
        boresight (beyond the waypoints' times, unless :attr:`extrapolate`, the first or
        last pose held).

        Parameters
        ----------
        t : array_like
            Times, s.

        Returns
        -------
        origin : (n, 3) numpy.ndarray
            The sensor's position, world frame.
        rotation : (n, 3, 3) numpy.ndarray
            Sensor-to-world rotation matrices.
        """
        t = np.asarray(t, np.float64).ravel()
        if self._one_attitude is not None:                          # one attitude: once
            pos = (np.broadcast_to(self.positions[0], (len(t), 3)) if len(self.times) == 1
                   else self._positions(t))
            mats, mount = self._one_attitude
            return pos + mount, np.broadcast_to(mats, (len(t), 3, 3))
        pos, rot = self._body(t)
        origin = pos + rot.apply(np.asarray(self.mount_offset))
        mats = (rot * rotation(np.asarray(self.boresight_deg))).as_matrix()
        return origin, mats.reshape(len(t), 3, 3)

    def sensor_velocities(self, t, step=_VELOCITY_STEP):
        """The sensor's velocity at times ``t``: its position's difference over ``step``
        either side, one-sided at the waypoints' first and last times (the pose is held
        beyond them, which a central difference there would halve); within ``step`` of a
        linear path's corner, a blend of its two legs'.

        Parameters
        ----------
        t : array_like
            Times, s.
        step : float
            The difference's half-step, s.

        Returns
        -------
        (n, 3) numpy.ndarray
            m/s, world frame.
        """
        t = np.asarray(t, np.float64).ravel()
        lo, hi = t - step, t + step
        if len(self.times) > 1 and not self.extrapolate:
            lo = np.maximum(lo, self.times[0])
            hi = np.minimum(hi, self.times[-1])
        span = hi - lo
        return ((self.sensor_poses(hi)[0] - self.sensor_poses(lo)[0])
                / np.where(span > 0, span, 1.0)[:, None])

    def describe(self) -> dict:
        """The platform's waypoints and mount, with units in the names (for result files).

        Returns
        -------
        dict
            ``times_s``, ``positions``, ``attitudes_deg``, ``interpolation``,
            ``mount_offset``, ``boresight_deg``, ``extrapolate``, ``time_origin_s`` and
            ``attitude_convention``.
        """
        return {"times_s": self.times.tolist(), "positions": self.positions.tolist(),
                "attitudes_deg": self.attitudes_deg.tolist(),
                "interpolation": self.interpolation, "mount_offset": list(self.mount_offset),
                "boresight_deg": list(self.boresight_deg), "extrapolate": self.extrapolate,
                "time_origin_s": self.time_origin,
                "attitude_convention": "roll, pitch, yaw: Rotation.from_euler('ZYX', "
                                       "[yaw, pitch, roll]), body x forward, y left, z up"}
