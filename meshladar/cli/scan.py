"""``meshladar scan``: a scanner's point cloud of a scene, to LAS/LAZ, HDF5 or ``.npz``.

``--pattern`` and ``--platform`` take a kind and ``key=value`` words, one string (a key
at most once): the keys are the Python constructor's keyword arguments
(:mod:`meshladar.scan.patterns`, :class:`meshladar.scan.Platform`, every platform's
``mount_offset`` and ``boresight_deg`` too), a value is a number, a comma list
(``0,0,1.5``), an evenly spaced range ``start:stop:count`` (``-15:15:32``), a word where
the keyword takes one (``interpolation=spline``) or ``true``/``false``. A waypoints
platform's ``positions`` and ``attitudes_deg`` are flat lists, three values a waypoint
(``positions=0,0,300,3,0,300``). A ``--platform`` ending in ``.csv`` is a trajectory
file; ``FILE.csv key=value ...`` gives it ``interpolation``, ``time_offset`` (the file's
time at the pattern's t = 0, s), ``mount_offset`` or ``boresight_deg``.
"""

from __future__ import annotations

import functools
import inspect
import math
import os
import re

import numpy as np

from .. import scan as scanning          # its modules load when a scan runs
from ..errors import ParameterError
from ..noise import Noise
from ..scan.formats import FORMATS, check_writable
from ..waveforms import GaussianPulse
from .checks import check_outdir, check_output
from .simulate import load_scene
from .words import flag_words

__all__ = ["cmd_scan", "parse_spec", "scan_words", "PLATFORM_KINDS", "BEAM_DEFAULTS"]

#: ``--platform`` kinds: each names its :class:`meshladar.scan.Platform` constructor.
PLATFORM_KINDS = ("static", "moving", "waypoints")
#: The keys every ``--platform`` takes besides its constructor's own (its ``**mount``).
MOUNT_KEYS = ("mount_offset", "boresight_deg")
#: A waypoints platform's keys given as flat lists, three values a waypoint.
ROW_KEYS = ("positions", "attitudes_deg")
#: The point files ``-o`` writes, by extension.
POINT_SUFFIXES = tuple(FORMATS)
#: The waveform files `--waveforms` writes (HDF5).
HDF5_SUFFIXES = tuple(k for k, (named, _) in FORMATS.items() if named == "HDF5")
#: The sensor's API arguments and the flags that set them (named in the messages).
SENSOR_FLAGS = {"max_returns": "--max-returns", "shots": "--geiger-shots",
                "dead_time": "--dead-time", "detection_efficiency": "--detection-efficiency",
                "false_alarm": "--false-alarm",
                "divergence": "--divergence", "sub_rays": "--sub-rays", "tol": "--tol",
                "pulse_energy": "--pulse-energy", "aperture_diameter": "--aperture",
                "sample_rate": "--sample-rate", "fwhm": "--pulse-fwhm",
                "background_rate": "--background-rate", "dark_rate": "--dark-rate"}
#: scan's messages in its flags' words (:func:`.words.flag_words`): the sensor's arguments,
#: the platform's (``platform: ...``, its coverage of the pattern's times), and the API's
#: advice naming what the command line sets by other flags or not at all.
scan_words = flag_words(
    {**SENSOR_FLAGS, "platform": "--platform"}, [n for n in SENSOR_FLAGS if "_" in n],
    [("raise the sensor's --pulse-energy or --aperture", "raise --pulse-energy or --aperture"),
     (", or lower its detector's threshold", ""),
     (", or its detector's --false-alarm (the threshold follows it)",
      ", or --false-alarm (the threshold follows it)"),
     (", or its GeigerMode's shots", ", or --geiger-shots"),
     ("or a wider pulse", "or a wider pulse (--pulse-fwhm)"),
     ("or a shorter pulse", "or a shorter pulse (--pulse-fwhm)"),
     ("detector: cfar applies to a linear receiver's records;",
      "--cfar applies to a linear receiver's records, not --geiger-shots;"),
     ("--platform: path: cannot read", "--platform: cannot read"),
     ("beam.tol=", "--tol "), ("beam.tol", "--tol"),
     ("(a platform at rest: Platform.static)",
      "(a platform at rest: --platform 'static position=X,Y,Z')")])
_TRUE, _FALSE = ("true", "yes", "on", "1"), ("false", "no", "off", "0")
#: The beam flags' values when not given (the parser leaves them None: whether one was
#: given decides what applies, a flash pattern refusing ``--divergence`` and ``--profile``);
#: ``profile`` and ``tol`` are ScanBeam's own defaults (tested; written out so that the
#: parser's help does not load the scanner).
BEAM_DEFAULTS = {"divergence": 5e-4, "profile": "gaussian", "tol": 0.1}
#: What a flash array does instead of a beam, for the flags it refuses.
_FLASH_PIXELS = ("its pixels are lit uniformly over their IFOV and sampled by m x m "
                 "sub-rays each, m = ceil(1/(2 tol)), set with --tol (default 0.1: 5 x 5)")


def _value(flag, key, text, default=None):
    if isinstance(default, bool):
        if text.lower() in _TRUE + _FALSE:
            return text.lower() in _TRUE
        raise ParameterError(f"{flag}: {key}={text!r} must be true or false")
    if isinstance(default, str):
        return text
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


def parse_spec(flag, text, kinds, extra=()):
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
    extra : sequence of str
        Numeric keys every kind takes besides its parameters (those its ``**kwargs``
        pass on).

    Returns
    -------
    tuple
        ``(constructor, {key: number, list, numpy.ndarray, str or bool})``: a value is
        a word for a parameter whose default is a string, true or false for a boolean's.

    Raises
    ------
    ParameterError
        When the kind is unknown, a word is not ``key=value`` of one of the constructor's
        parameters, a key is given twice, a required key is missing, or a value is not a
        number, a comma list or ``start:stop:count`` (or true/false for a boolean).
    """
    words = text.split() if isinstance(text, str) else []
    if not words or words[0] not in kinds:
        raise ParameterError(f"{flag}: the kind must be one of {sorted(kinds)}; got "
                             f"{text!r}")
    make = kinds[words[0]]
    defaults = {n: p.default for n, p in inspect.signature(make).parameters.items()
                if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    defaults.update({n: None for n in extra})
    kwargs = {}
    for word in words[1:]:
        key, eq, val = word.partition("=")
        if not eq or key not in defaults:
            raise ParameterError(f"{flag}: {words[0]} takes {', '.join(defaults)} as "
                                 f"key=value; got {word!r}")
        if key in kwargs:
            raise ParameterError(f"{flag}: {key} is given twice; give each key once")
        kwargs[key] = _value(flag, key, val, defaults[key])
    missing = [n for n, d in defaults.items() if d is inspect.Parameter.empty
               and n not in kwargs]
    if missing:
        raise ParameterError(f"{flag}: {words[0]} needs {', '.join(missing)} as key=value "
                             f"(it takes {', '.join(defaults)}); got {text!r}")
    for key in ("rows", "columns", "frames"):
        if isinstance(kwargs.get(key), float) and kwargs[key].is_integer():
            kwargs[key] = int(kwargs[key])
    return make, kwargs


def _build(make, kwargs, flag):
    """``make(**kwargs)`` (its keys checked by :func:`parse_spec`), its refusal named as
    ``flag``'s."""
    try:
        return make(**kwargs)
    except ParameterError as exc:
        raise ParameterError(f"{flag}: {exc}") from None


def _rows(key, value):
    """A flat list of a waypoints key as (n, 3) rows."""
    a = np.atleast_1d(np.asarray(value, np.float64)).ravel()
    if a.size % 3:
        raise ParameterError(f"--platform: {key} takes three values a waypoint, in turn "
                             f"(x,y,z,x,y,z...), a multiple of 3; got {a.size}")
    return a.reshape(-1, 3)


def _platform(text):
    """The ``--platform`` of the module docstring: a platform kind's spec, a trajectory
    file, or a trajectory file and its keys."""
    found = _trajectory(text)
    if found and not found[1]:
        return _build(scanning.Platform.from_csv, {"path": found[0]}, "--platform")
    if found:
        kinds = {"trajectory": functools.partial(scanning.Platform.from_csv, found[0])}
        text = "trajectory " + found[1]
    else:
        kinds = {kind: getattr(scanning.Platform, kind) for kind in PLATFORM_KINDS}
    make, kwargs = parse_spec("--platform", text, kinds, MOUNT_KEYS)
    for key in ROW_KEYS:
        if key in kwargs and make == scanning.Platform.waypoints:
            kwargs[key] = _rows(key, kwargs[key])
    return _build(make, kwargs, "--platform")


def _trajectory(text):
    """(path, its keys) where ``--platform`` starts with a trajectory file (its name up to
    the first ``.csv`` that ends a word: a name with spaces too), else None."""
    if text.lower().endswith(".csv") and os.path.exists(text):     # a whole name
        return text, ""
    found = re.match(r"\s*(.*?\.csv)(?:\s+(.*?))?\s*$", text, re.IGNORECASE | re.DOTALL)
    return (found.group(1), found.group(2) or "") if found else None


def _check_discrete(args):
    """``--discrete`` makes no records: the flags that need them are refused; and
    ``--noise`` with ``--geiger-shots``, whose detections are always drawn."""
    given = [f for f, v in (("--geiger-shots", args.geiger_shots), ("--noise", args.noise),
                            ("--background-rate", args.background_rate),
                            ("--dark-rate", args.dark_rate), ("--cfar", args.cfar),
                            ("--waveforms", args.waveforms)) if v]
    if args.discrete and given:
        raise ParameterError(f"--discrete makes no waveform records: {given[0]} does not "
                             "apply (leave out --discrete for waveforms)")
    if args.noise and args.geiger_shots:
        raise ParameterError("--noise does not apply with --geiger-shots: a Geiger-mode "
                             "pixel's detections are always drawn, photon by photon "
                             "(leave out --noise)")


def _check_beam(args, flash):
    """The beam's flags that apply: ``--tol`` or ``--sub-rays``, not both; a flash pattern
    takes only ``--tol``."""
    if args.tol is not None and args.sub_rays is not None:
        raise ParameterError("--tol and --sub-rays both set the sub-rays per pulse; give "
                             "one (--tol T | --sub-rays N)")
    given = [f for f, v in (("--sub-rays", args.sub_rays),
                            ("--divergence", args.divergence), ("--profile", args.profile))
             if v is not None]
    if flash and given:
        raise ParameterError(f"{given[0]} does not apply to a flash pattern: "
                             f"{_FLASH_PIXELS}; leave {given[0]} out")


def _beam(args, flash):
    """The ScanBeam of the flags, its sub-rays checked (a flash pattern's: its pixels')."""
    tol = BEAM_DEFAULTS["tol"] if args.tol is None else args.tol
    if flash:                             # the beam's tol alone: m x m sub-rays a pixel
        beam = scanning.ScanBeam(0.0, tol=tol)
        scanning.footprint.check_flash_beam(beam)
        return beam
    beam = scanning.ScanBeam(
        BEAM_DEFAULTS["divergence"] if args.divergence is None else args.divergence,
        profile=args.profile or BEAM_DEFAULTS["profile"], tol=tol, sub_rays=args.sub_rays)
    beam.offsets()                        # refuses a --tol that needs too many sub-rays
    return beam


def _sensor(args, flash):
    """The ScanSensor of the flags (the API's refusals put in the flags' words by
    :data:`scan_words`)."""
    _check_discrete(args)
    noise = None
    if args.background_rate or args.dark_rate or args.noise:
        noise = Noise(background_rate=args.background_rate, dark_rate=args.dark_rate)
    geiger = None
    if args.geiger_shots:
        geiger = scanning.GeigerMode(
            shots=args.geiger_shots, detection_efficiency=args.detection_efficiency or 1.0,
            dead_time=math.inf if args.dead_time is None else args.dead_time)
    else:
        given = [f for f, v in (("--dead-time", args.dead_time),
                                ("--detection-efficiency", args.detection_efficiency))
                 if v is not None]
        if given:
            raise ParameterError(f"{given[0]} sets a Geiger-mode array's pixels: give "
                                 "--geiger-shots K too, or leave it out")
    return scanning.ScanSensor(
        pulse_energy=args.pulse_energy, aperture_diameter=args.aperture,
        sample_rate=args.sample_rate, pulse=GaussianPulse(args.pulse_fwhm),
        beam=_beam(args, flash), noise=noise, geiger=geiger,
        detector=scanning.Detector(max_returns=args.max_returns, cfar=args.cfar,
                                   false_alarm=args.false_alarm or 1e-6),
        echoes="discrete" if args.discrete else "waveform")


def _check_outputs(args):
    """-o and --waveforms: writable files of known formats, never an input, never one
    file (compared as real paths: links resolved)."""
    found = _trajectory(args.platform)
    inputs = [args.scene, args.materials, args.run_dir] + ([found[0]] if found else [])
    check_output(args.output, POINT_SUFFIXES, inputs, run_dir=args.run_dir)
    check_writable(args.output, "-o", folder=False)        # a missing folder: made
    if args.run_dir is not None:
        if args.waveforms is not None:
            raise ParameterError("--waveforms streams the records as the scan runs; a "
                                 "--run-dir run resumes from its chunks: give one of them")
        check_outdir(args.run_dir, "--run-dir")
    if args.waveforms is not None:
        check_output(args.waveforms, HDF5_SUFFIXES, inputs, "--waveforms",
                     others=[("-o", args.output)])
        check_writable(args.waveforms, "--waveforms", folder=False)


def cmd_scan(args) -> int:
    """Scan a scene with a pattern from a platform and write its point cloud (LAS 1.4, LAZ,
    HDF5 or numpy's .npz by -o's extension), each return with its ground truth (part, face, true range
    and point); --waveforms also streams every pulse's record to HDF5 as the scan runs.

    Parameters
    ----------
    args : argparse.Namespace
        ``scene``, ``material``, ``coating``, ``materials`` (as ``simulate``'s),
        ``pattern`` and ``platform`` (module docstring), the sensor's flags, ``run_dir``
        (a resumable run folder: the same command run again computes only the chunks it
        lacks), ``output``,
        ``waveforms``, ``seed`` and ``quiet``.

    Returns
    -------
    int
        0, the exit status.
    """
    _check_outputs(args)
    make, kwargs = parse_spec("--pattern", args.pattern, scanning.PATTERNS)
    _check_beam(args, make is scanning.PATTERNS.get("flash"))
    pattern = _build(make, kwargs, "--pattern")
    platform = _platform(args.platform)
    platform.check_covers(pattern.times)
    sensor = _sensor(args, pattern.is_flash)
    scene, _, _ = load_scene(args)
    if not scene.is_mesh:
        scene = scene.tessellate()
    for path in (args.output, args.waveforms):      # every check passed: missing folders
        if path is not None:
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    cloud = scanning.scan(scene, pattern, platform, sensor, seed=args.seed,
                          waveforms_file=args.waveforms, progress=not args.quiet,
                          run_dir=args.run_dir)
    writer = FORMATS[os.path.splitext(args.output)[1].lower()][1]
    getattr(scanning, writer)(args.output, cloud)
    if not args.quiet:
        pts = cloud.points
        print(f"{len(pts)} returns from {len(pattern)} pulses -> {args.output}"
              + (f" (max {int(pts['number_of_returns'].max())} per pulse)" if len(pts) else ""))
    return 0
