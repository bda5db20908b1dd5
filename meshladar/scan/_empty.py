"""Why a scan recorded no return, said once its chunks are in (:func:`warn_empty`): no
pulse met the scene, a fixed record length cut the echoes, or the echoes were too weak for
the detector; with where the sensor was and where the scene is. A chunk without a record
counts what met the scene (:func:`pulses_lit`); a scan is empty only where every chunk is.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import EmptyScanWarning, user_stacklevel

__all__ = ["pulses_lit", "warn_empty"]


def pulses_lit(cast, pe):
    """(pulses a sub-ray of which met the scene, the most photoelectrons one pulse returned
    in all before noise): its sub-rays' positive ones, as the echoes count them. Made
    only for a chunk without a record (0.6 ms for 131,072 sub-rays, some 5 % of a chunk's
    scan): a scan is empty only where every chunk is."""
    met = np.count_nonzero((cast.face >= 0).any(axis=1))
    return met, float(np.where(pe > 0.0, pe, 0.0).sum(axis=1).max(initial=0.0))


def warn_empty(results, job, cut):
    """Say why a scan recorded no return: no pulse met the scene, a fixed record length
    (``cut``: the length that holds them, or None) dropped the returns, or the echoes were
    too weak; with where the sensor was and where the scene is (a scene in millimetres,
    read as metres, lies a thousand times farther)."""
    pattern, sensor = job.pattern, job.sensor
    one = "pixel" if pattern.is_flash else "pulse"
    pulses = f"{len(pattern)} {one}s"
    at = job.platform.sensor_poses(pattern.times[:1])[0][0]
    lo, hi = job.scene.bounds()
    where = (f"the sensor at {np.array2string(at, precision=4)} at the first pulse, the "
             f"scene{'' if job.split is None else ' at rest'} within "
             f"{np.array2string(lo, precision=4)} to {np.array2string(hi, precision=4)}, its "
             f"centre {np.linalg.norm(0.5 * (lo + hi) - at):.4g} m away; a scan's units are "
             "metres")
    lit = [r["lit"] for r in results if "lit" in r]
    met, top = (int(sum(x[0] for x in lit)), max(x[1] for x in lit)) \
        if len(lit) == len(results) and lit else (None, None)
    if cut is not None:
        why = (f"samples={sensor.samples} cut the echoes of the pulses that met the scene "
               f"(samples={cut} holds them all: the RecordLengthWarning) ({where})")
    elif met is None:
        why = f"the chunks read from an older run folder do not say more ({where})"
    elif met:
        why = (f"{met} of {pulses} met the scene, but {_undetected(sensor)} (the brightest "
               f"{one} returned {top:.3g} photoelectrons in all, before noise, spread over "
               f"its echoes' samples): raise the sensor's pulse_energy or aperture_diameter"
               f"{_lower(sensor)} ({where})")
    else:
        why = (f"none of the {pulses} met the scene ({where}): check the platform's "
               "position and attitude (the sensor looks along its x; a beam that starts on "
               "a surface ranges nothing) and the pattern's angles")
    warnings.warn(f"the scan recorded no return: {why}", EmptyScanWarning,
                  stacklevel=user_stacklevel())


def _undetected(sensor):
    if sensor.geiger is not None:
        return "no echo stood out of a Geiger-mode pixel's histogram"
    if sensor.echoes == "discrete":
        return (f"no return reached the {sensor.detector.threshold or 1.0:g} photoelectrons "
                "a discrete return needs")
    return "no echo crossed the detection threshold (photoelectrons per sample)"


def _lower(sensor):
    det = sensor.detector
    if sensor.geiger is not None:
        return ", or its GeigerMode's shots"
    if sensor.echoes == "discrete" or det.threshold is not None:
        return ", or lower its detector's threshold"
    return "" if det.cfar else ", or its detector's false_alarm (the threshold follows it)"
