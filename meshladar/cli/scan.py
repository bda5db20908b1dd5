"""``meshladar scan``: a scanner's point cloud of a scene, to LAS/LAZ or HDF5.

``--pattern`` and ``--platform`` take a kind and ``key=value`` words, one string: the
keys are the Python constructor's keyword arguments (:mod:`meshladar.scan.patterns`,
:class:`meshladar.scan.Platform`), a value is a number, a comma list (``0,0,1.5``) or an
evenly spaced range ``start:stop:count`` (``-15:15:32``). A ``--platform`` ending in
``.csv`` is a trajectory file.
"""

from __future__ import annotations

import inspect

import numpy as np

from .. import scan as scanning          # its modules load when a scan runs
from ..errors import ParameterError
from ..noise import Noise
from ..scan.files import check_writable
from ..waveforms import GaussianPulse
from .checks import check_output
from .simulate import load_scene

__all__ = ["cmd_scan", "parse_spec", "PLATFORM_KINDS"]

#: ``--platform`` kinds: each names its :class:`meshladar.scan.Platform` constructor.
PLATFORM_KINDS = ("static", "moving", "waypoints")
#: The point files ``-o`` writes, by extension.
POINT_SUFFIXES = (".las", ".laz", ".h5", ".hdf5")


def _value(flag, key, text):
    try:
        if text.count(":") == 2:
            lo, hi, n = text.split(":")
            if float(n) != int(float(n)) or int(float(n)) < 1:
                raise ValueError
            return np.linspace(float(lo), float(hi), int(float(n)))
        if "," in text:
            return [float(x) for x in text.split(",")]
        return float(text)
    except ValueError:
        raise ParameterError(f"{flag}: {key}={text!r} is not a number, a comma list or "
                             "start:stop:count") from None


def parse_spec(flag, text, kinds):
    """``(constructor, keyword arguments)`` from a ``KIND key=value ...`` string, checked
    against the kind's constructor's parameters (named in the messages).

    Parameters
    ----------
    flag : str
        The option's name, for the messages (``"--pattern"``).
    text : str
        The option's value.
    kinds : dict of str to callable
        The constructors by kind.

    Returns
    -------
    tuple
        ``(constructor, {key: number, list or numpy.ndarray})``.

    Raises
    ------
    ParameterError
        When the kind is unknown, a word is not ``key=value`` of one of the constructor's
        parameters, or a value is not a number, a comma list or ``start:stop:count``.
    """
    words = text.split() if isinstance(text, str) else []
    if not words or words[0] not in kinds:
        raise ParameterError(f"{flag}: the kind must be one of {sorted(kinds)}; got "
                             f"{text!r}")
    make = kinds[words[0]]
    params = [n for n, p in inspect.signature(make).parameters.items()
              if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    kwargs = {}
    for word in words[1:]:
        key, eq, val = word.partition("=")
        if not eq or key not in params:
            raise ParameterError(f"{flag}: {words[0]} takes {', '.join(params)} as key=value; "
                                 f"got {word!r}")
        kwargs[key] = _value(flag, key, val)
    for key in ("rows", "columns", "frames"):
        if isinstance(kwargs.get(key), float) and kwargs[key].is_integer():
            kwargs[key] = int(kwargs[key])
    return make, kwargs


def _build(make, kwargs, flag):
    try:
        return make(**kwargs)
    except TypeError as exc:            # a required key missing
        raise ParameterError(f"{flag}: {exc}") from None
    except ParameterError as exc:
        raise ParameterError(f"{flag}: {exc}") from None


def _platform(args):
    if args.platform.lower().endswith(".csv"):
        return _build(scanning.Platform.from_csv, {"path": args.platform}, "--platform")
    kinds = {kind: getattr(scanning.Platform, kind) for kind in PLATFORM_KINDS}
    make, kwargs = parse_spec("--platform", args.platform, kinds)
    return _build(make, kwargs, "--platform")


def _sensor(args):
    noise = None
    if args.background_rate or args.dark_rate or args.noise:
        noise = Noise(background_rate=args.background_rate, dark_rate=args.dark_rate)
    geiger = scanning.GeigerMode(shots=args.geiger_shots) if args.geiger_shots else None
    beam = scanning.ScanBeam(args.divergence, profile=args.profile, tol=args.tol,
                             sub_rays=args.sub_rays)
    detector = scanning.Detector(max_returns=args.max_returns, cfar=args.cfar)
    return scanning.ScanSensor(pulse_energy=args.pulse_energy, aperture_diameter=args.aperture,
                               sample_rate=args.sample_rate,
                               pulse=GaussianPulse(args.pulse_fwhm), beam=beam, noise=noise,
                               geiger=geiger, detector=detector,
                               echoes="discrete" if args.discrete else "waveform")


def cmd_scan(args) -> int:
    """Scan a scene with a pattern from a platform and write its point cloud (LAS 1.4, LAZ
    or HDF5 by -o's extension), each return with its ground truth (part, face, true range
    and point); --waveforms also streams every pulse's record to HDF5 as the scan runs.

    Parameters
    ----------
    args : argparse.Namespace
        ``scene``, ``material``, ``coating``, ``materials`` (as ``simulate``'s),
        ``pattern`` and ``platform`` (module docstring), the sensor's flags, ``output``,
        ``waveforms``, ``seed`` and ``quiet``.

    Returns
    -------
    int
        0, the exit status.
    """
    inputs = [args.scene, args.materials, args.platform]
    check_output(args.output, POINT_SUFFIXES, inputs)
    check_writable(args.output, "-o")
    if args.waveforms is not None:
        check_output(args.waveforms, (".h5", ".hdf5"), inputs + [args.output], "--waveforms")
        check_writable(args.waveforms, "--waveforms")
    make, kwargs = parse_spec("--pattern", args.pattern, scanning.PATTERNS)
    pattern = _build(make, kwargs, "--pattern")
    platform = _platform(args)
    sensor = _sensor(args)
    scene, _, _ = load_scene(args)
    if not scene.is_mesh:
        scene = scene.tessellate()
    cloud = scanning.scan(scene, pattern, platform, sensor, seed=args.seed,
                          waveforms_file=args.waveforms, progress=not args.quiet)
    if args.output.lower().endswith((".h5", ".hdf5")):
        scanning.write_hdf5(args.output, cloud)
    else:
        scanning.write_las(args.output, cloud)
    if not args.quiet:
        pts = cloud.points
        print(f"{len(pts)} returns from {len(pattern)} pulses -> {args.output}"
              + (f" (max {int(pts['number_of_returns'].max())} per pulse)" if len(pts) else ""))
    return 0
