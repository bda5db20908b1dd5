"""The imaging ladar's benchmark (``meshladar bench``'s scan lines): a rotating 32-channel
head at 10 Hz and 3e5 pulses/s, 16 sub-rays per pulse, inside an 82k-triangle sphere (every
sub-ray hits), against the bare packet cast of the same sub-rays in the same process,
interleaved, in CPU seconds; and a 128 × 128 flash frame's rate with 512-sample waveforms.
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace

import numpy as np

from ..brdf import Lambertian
from ..meshes import sphere
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import embree_scene, geometry
from ..scan import Platform, ScanBeam, ScanSensor, flash, rotating, scan
from ..scan.cast import world_directions
from ..scene import Scene

__all__ = ["bench_scan"]


def _cpu(fn):
    t = time.process_time()
    fn()
    return time.process_time() - t


def _wall(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def _two_threads(emb, o32, d32):
    """The bare cast of the same sub-rays, half on each of two threads."""
    half = len(o32) // 2
    other = threading.Thread(target=emb.run, args=(o32[half:], d32[half:]))
    other.start()
    emb.run(o32[:half], d32[:half])
    other.join()


def bench_scan(*, subdivisions=6, duration=0.1, rounds=3):
    """Sub-rays per CPU-second of :func:`meshladar.scan.scan` (one thread, two threads)
    against the bare packet cast of the same sub-rays, medians of interleaved rounds; and
    a 128 × 128 flash frame of 512-sample waveforms per second (wall clock).

    Parameters
    ----------
    subdivisions : int
        The sphere's icosphere level (6: 81 920 triangles).
    duration : float
        Seconds of scanning (0.1: 30 000 pulses).
    rounds : int
        Interleaved rounds.

    Returns
    -------
    dict
        ``faces``, ``sub_rays``, ``packet_mrays``, ``scan_mrays``, ``scan_over_cast``,
        ``discrete_mrays`` and ``discrete_over_cast`` (``echoes="discrete"``: no
        records), ``two_over_one`` (wall-clock speed-up of two threads, waveforms),
        ``cast_two_over_one`` (the same for the bare cast of the same sub-rays, half on
        each thread: what two threads give on this machine now, the reference for
        ``two_over_one`` on a shared or throttled machine), ``flash_fps``.
    """
    part = sphere((0.0, 0.0, 0.0), 30.0, 0, subdivisions=subdivisions)
    scene = Scene.from_parts([part], [Lambertian(0.3)])
    pattern = rotating(np.linspace(-15, 15, 32), rotation_hz=10, pulse_rate=3e5,
                       duration=duration)
    platform = Platform.static((0.5, 0.2, 0.1))
    sensor = ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                        beam=ScanBeam(5e-4, sub_rays=16))
    origins, rot = platform.sensor_poses(pattern.times)
    dirs = world_directions(rot, pattern.directions, sensor.beam.offsets()).reshape(-1, 3)
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, resolve_backend("auto"))
    o32 = np.ascontiguousarray(np.repeat(origins - geo.center, 16, axis=0), np.float32)
    d32 = np.ascontiguousarray(dirs, np.float32)
    emb.run(o32[:4096], d32[:4096])
    discrete = replace(sensor, echoes="discrete")
    scan(scene, pattern, platform, sensor, jobs=1)                    # warm-up: compile
    scan(scene, pattern, platform, discrete, jobs=1)
    cast, one, fast, wall1, wall2, bare1, bare2 = [], [], [], [], [], [], []
    for _ in range(rounds):
        cast.append(_cpu(lambda: emb.run(o32, d32)))
        bare1.append(_wall(lambda: emb.run(o32, d32)))
        bare2.append(_wall(lambda: _two_threads(emb, o32, d32)))
        t = time.perf_counter()
        one.append(_cpu(lambda: scan(scene, pattern, platform, sensor, jobs=1)))
        wall1.append(time.perf_counter() - t)
        t = time.perf_counter()
        scan(scene, pattern, platform, sensor, jobs=2)
        wall2.append(time.perf_counter() - t)
        fast.append(_cpu(lambda: scan(scene, pattern, platform, discrete, jobs=1)))
    n = len(o32)
    frame = flash(128, 128, ifov_deg=0.05)
    fsensor = ScanSensor(pulse_energy=1e-3, aperture_diameter=0.05, sample_rate=2e9,
                         samples=512, beam=ScanBeam(0.0, tol=0.5))
    scan(scene, frame, platform, fsensor, keep_waveforms=True)
    t = time.perf_counter()
    scan(scene, frame, platform, fsensor, keep_waveforms=True)
    flash_s = time.perf_counter() - t
    return {"faces": len(part.faces), "sub_rays": n,
            "packet_mrays": n / np.median(cast) / 1e6, "scan_mrays": n / np.median(one) / 1e6,
            "scan_over_cast": float(np.median(cast) / np.median(one)),
            "discrete_mrays": n / np.median(fast) / 1e6,
            "discrete_over_cast": float(np.median(cast) / np.median(fast)),
            "two_over_one": float(np.median(wall1) / np.median(wall2)),
            "cast_two_over_one": float(np.median(bare1) / np.median(bare2)),
            "flash_fps": 1.0 / flash_s}
