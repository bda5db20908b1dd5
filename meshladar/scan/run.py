"""``scan``: the point cloud a scanner on a platform records from a mesh scene.

Per chunk of pulses: the sensor's pose at each pulse's emission time (:mod:`.platforms`),
the pulse's sub-rays (:mod:`.footprint`) turned into the world, their first hits and
photoelectrons (:mod:`.cast`), the pulse's waveform, its noise and its returns
(:mod:`.echoes`), each return's position along the pulse's axis at the measured range
c t / 2, and its ground truth: the sub-rays whose echoes lie nearest it in time give its
photoelectron-weighted true range and hit point, and the strongest of them its part and
face. A return no sub-ray explains (a false alarm) has true part and face −1 and nan truth.
"""

from __future__ import annotations

import contextlib
import math
import warnings

import numpy as np
from scipy.special import ndtri

from .._validate import check_count, check_seed
from ..errors import MeshladarWarning, ParameterError, RecordLengthWarning, user_stacklevel
from ..noise import draw_noise
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import geometry
from ..scene import Scene
from ..stream import run_chunks
from ..sensor import SPEED_OF_LIGHT
from ._empty import pulses_lit, warn_empty
from ._kernels import discrete_returns
from ._records import fill_records
from ._sampling import lit_spans
from .cast import cast_static, photoelectrons, world_directions
from .echoes import (CENTROID_SIGMAS, Returns, cfar_background, echo_shape, find_returns,
                     record_blocks, record_samples, waveforms_with_echoes)
from .files import WaveformSink
from .footprint import check_flash_beam, describe_pixels, pixel_offsets
from .geiger import blind_shots, coates, fire
from .instrument import FWHM_PER_SIGMA, ScanSensor
from .moving import at_wavelength, cast_moving, doppler, moving_parts
from .patterns import ScanPattern
from .platforms import Platform
from .points import CONVENTIONS, POINT_DTYPE, PointCloud
from ._streaming import ScanJob, chunk_arrays, job_description, records, scan_chunk

__all__ = ["scan", "CHUNK_RAYS", "RECORD_SAMPLES", "GEIGER_PILEUP_SHOTS"]

#: Sub-rays cast per chunk (a chunk's pulses × sub-rays per pulse).
CHUNK_RAYS = 1 << 17
#: The most samples a chunk's records hold at once where they are not kept (64 MiB of
#: float64): beyond it they are made and searched in runs of pulses (a deep scene).
RECORD_SAMPLES = 1 << 23
#: Geiger-mode arrays of at least this many shots a pulse are checked for pile-up: a
#: return reading ln K events per shot or more, about the most Coates' correction of K
#: shots reads (1000 shots of a 5 ns pulse: 8 events read 0.91 of them, 5 cm early; 20
#: read 0.37, 32 cm early; 4 within 3 % and 1 cm). Fewer shots estimate too coarsely.
GEIGER_PILEUP_SHOTS = 10


def _check(scene, pattern, platform, sensor):
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("scene must be a mesh Scene (Scene.from_mesh, Scene.tessellate)")
    for name, value, kind in (("pattern", pattern, ScanPattern),
                              ("platform", platform, Platform),
                              ("sensor", sensor, ScanSensor)):
        if not isinstance(value, kind):
            raise ParameterError(f"{name} must be a {kind.__name__}; got "
                                 f"{type(value).__name__}")
    platform.check_covers(pattern.times)          # a trajectory must span the pulses
    if pattern.is_flash:                          # its pixels take only the beam's tol
        check_flash_beam(sensor.beam)


def _footprint(pattern, sensor):
    """Sub-ray offsets, their energy shares, and the flash pixel pitch (or None)."""
    if pattern.is_flash:
        off = pixel_offsets(sensor.beam.tol)
        pixels = pattern.shape[0] * pattern.shape[1]
        return off, np.full(len(off), 1.0 / (len(off) * pixels)), \
            float(np.tan(np.radians(pattern.ifov_deg)))
    off = sensor.beam.offsets()
    return off, np.full(len(off), 1.0 / len(off)), None


def _sensor_info(pattern, sensor):
    """The sensor's parameters as the scan used them: a flash array's beam is its pixels'
    sampling (:func:`.footprint.describe_pixels`), not the beam it ignores."""
    out = sensor.describe()
    if pattern.is_flash:
        out["beam"] = describe_pixels(sensor.beam, pattern.ifov_deg)
    return out


_NO_SHIFT = np.zeros((0, 0))


def _chunk(job, sl, seed):
    """One chunk's records, the blocks of its measured waveforms (when kept: ``[(first
    pulse in the chunk, records, starts), …]``), the record length each pulse's
    echoes need where the sensor fixes it (else None), and
    ``_empty.pulses_lit`` where the chunk has no record (else None)."""
    scene, pattern, platform, sensor = job.scene, job.pattern, job.platform, job.sensor
    offsets, shares, pitch = job.foot
    t = pattern.times[sl]
    origins, rot = platform.sensor_poses(t)
    local = pattern.directions[sl]
    axis = np.einsum("nij,nj->ni", rot, local)
    if job.split is None:
        cast = cast_static(scene, origins, rot, local, offsets, pitch, job.backend, sensor,
                           shares)
    else:
        cast = cast_moving(job.split, origins, world_directions(rot, local, offsets, pitch),
                           t, job.backend)
    pe = cast.pe if cast.pe is not None else photoelectrons(scene, cast, shares, sensor)
    still = job.split is None and platform.is_static      # no Doppler shift to weigh
    shift = _NO_SHIFT if still else doppler(job.split, platform, cast, origins, t,
                                            sensor.wavelength)
    tau = 2.0 * cast.distance / SPEED_OF_LIGHT
    if sensor.echoes == "discrete":
        ret, blocks, needed = _discrete(sensor, tau, pe), None, None
    else:
        ret, blocks, needed = _waveform_returns(job, tau, pe, seed)
        ret.time = ret.time - sensor.delay             # the shape's own delay taken off
    rec = np.empty(len(ret), POINT_DTYPE)
    fill_records(rec, (ret.pulse, np.ascontiguousarray(ret.time, np.float64), ret.amplitude,
                       ret.width, ret.intensity, ret.return_number, ret.number_of_returns,
                       _truth_reach(sensor, ret)),
                 (sl.start, t, pattern.scan_angles_deg[sl], pattern.channels[sl],
                  _walk(sensor, pe)),
                 (origins, axis, 0.5 * SPEED_OF_LIGHT),
                 (tau, pe, cast.distance, cast.points, cast.face, shift), job.part_of)
    lit = None if len(rec) else pulses_lit(cast, pe)  # asked only where a scan is empty
    return rec, (blocks if job.keep or job.sink is not None else None), needed, lit


def _truth_reach(sensor, ret):
    """How far in time (s) a sub-ray's echo may lie from a return for the return's ground
    truth: :data:`.echoes.CENTROID_SIGMAS` of its echo's σ (its fitted width's, at least
    the pulse's): a false alarm of the noise away from every echo has none. Discrete
    returns are the sub-rays' own groups (no noise): each takes its nearest sub-rays."""
    if sensor.echoes == "discrete":
        return np.full(len(ret), np.inf)
    return CENTROID_SIGMAS * np.maximum(ret.width / FWHM_PER_SIGMA, sensor.sigma)


def _walk(sensor, pe):
    """Each pulse's further reach (s) for a return earlier than its echo: a Geiger-mode
    pixel's first photon comes where the echo's cumulative events per shot reach about
    one, −Φ⁻¹(1/N) σ before its centre (N its events per shot); none in linear mode."""
    if sensor.geiger is None:
        return np.zeros(len(pe))
    events = sensor.geiger.detection_efficiency * pe.sum(axis=1)
    with np.errstate(divide="ignore"):
        return sensor.sigma * np.maximum(0.0, -ndtri(np.minimum(1.0 / events, 0.5)))


def _waveform_returns(job, tau, pe, seed):
    """The returns of a chunk's records (:func:`_detect`), the blocks of its records as
    measured, ``[(first pulse, records, starts), …]``, and, where the sensor fixes their
    length, each pulse's needed length (else None). Records of the default length are
    made in runs of pulses of at most :data:`RECORD_SAMPLES` samples
    (:func:`.echoes.record_blocks`, one run where the chunk's fit), each run's noise
    seeded by ``seed`` and the run's first pulse (the chunk's own seed where it is one
    run): a deep scene's few long records do not make every record of the chunk long.
    The runs depend on the chunk's echoes alone, not on whether the records are kept."""
    sensor = job.sensor
    shape = echo_shape(sensor.pulse, sensor.response, sensor.dt)
    spans = lit_spans(tau, pe)
    runs = ([(0, len(tau))] if sensor.samples is not None
            else record_blocks(spans, sensor.sigma, sensor.dt, shape, RECORD_SAMPLES))
    found, blocks = [], []
    for lo, hi in runs:
        waves, start, echoes = waveforms_with_echoes(
            tau[lo:hi], pe[lo:hi], sensor.sigma, sensor.dt, sensor.samples, shape,
            (spans[0][lo:hi], spans[1][lo:hi]))
        run_seed = seed if len(runs) == 1 or seed is None else list(seed) + [lo]
        ret, measured = _detect(sensor, waves, start, run_seed, echoes)
        found.append((ret.pulse + lo, ret.time, ret.amplitude, ret.width, ret.intensity))
        blocks.append((lo, measured, start))
    ret = Returns(*(np.concatenate(x) for x in zip(*found)))
    needed = None
    if sensor.samples is not None:                     # a fixed length may cut echoes
        needed = record_samples(spans, blocks[0][2], sensor.sigma, sensor.dt, shape)
        ret = _within_records(ret, blocks[0][2], needed, sensor)
    return ret, blocks, needed


def _info(pattern, platform, sensor, seed, motions):
    """A scan's ``info``: its conventions and everything that made it."""
    return {"conventions": dict(CONVENTIONS), "pattern": pattern.describe(),
            "platform": platform.describe(), "sensor": _sensor_info(pattern, sensor),
            "seed": seed, "motions": {str(k): m.describe() for k, m in (motions or {}).items()}}


def _within_records(ret, start, needed, sensor):
    """``ret`` less the returns of pulses whose echoes a fixed record cut (``needed`` more
    samples than it holds) whose centroid window (:data:`.echoes.CENTROID_SIGMAS` σ either
    side) reaches past the record's end: a centroid there is pulled early."""
    samples = sensor.samples
    if not np.any(needed > samples):
        return ret
    p = ret.pulse
    end = start[p] + samples * sensor.dt
    keep = (needed[p] <= samples) | (ret.time + CENTROID_SIGMAS * sensor.sigma <= end)
    return Returns(p[keep], ret.time[keep], ret.amplitude[keep], ret.width[keep],
                   ret.intensity[keep])


def _warn_cut(results, sensor, pulses):
    """Warn where a fixed record length cut some pulses' echoes (their returns there were
    dropped: :func:`_within_records`), naming the length that holds them all; return that
    length (None where none was cut)."""
    if sensor.samples is None or sensor.echoes == "discrete" or not results:
        return None
    needed = np.concatenate([np.asarray(r["needed"]).ravel() for r in results])
    cut = needed > sensor.samples
    if cut.any():
        warnings.warn(f"samples={sensor.samples}: the echoes of {int(cut.sum())} of {pulses} "
                      "pulses end past their records (a record starts at its pulse's "
                      "first echo less its support): a return whose centroid window the "
                      "record cuts is dropped; "
                      f"samples={int(needed.max())} holds them all, or leave samples unset",
                      RecordLengthWarning, stacklevel=user_stacklevel())
        return int(needed.max())
    return None


def _discrete(sensor, tau, pe):
    """Discrete returns (:class:`~meshladar.scan.instrument.ScanSensor`'s ``echoes``):
    a pulse's sub-rays grouped in time, no record, no noise."""
    det = sensor.detector
    n = len(tau) * det.max_returns
    p, t = np.empty(n, np.int64), np.empty(n)
    e, w = np.empty(n), np.empty(n)
    k = discrete_returns(tau, pe, sensor.fwhm, det.threshold or 1.0, det.max_returns, p, t, e, w)
    spread = np.sqrt(sensor.sigma ** 2 + w[:k] ** 2)          # the pulse and the group
    return Returns(p[:k], t[:k], e[:k] * sensor.dt / (spread * math.sqrt(2 * math.pi)),
                   FWHM_PER_SIGMA * spread, e[:k])


def _detect(sensor, waves, start, seed, echoes=None):
    """The returns of a chunk's expected waveforms, through the sensor's noise and
    detector (linear mode) or its Geiger-mode pixels; and the records it measured.
    ``echoes``: each record's one echo (:func:`.echoes.waveforms_with_echoes`), whose
    filtered samples stand for the record's where it is measured as it is (no noise)."""
    det, b = sensor.detector, sensor.background()
    if sensor.geiger is not None:
        gm = sensor.geiger
        dead = gm.dead_samples(sensor.dt)
        lam = gm.detection_efficiency * waves + b
        hist = fire(lam, gm.shots, dead, np.random.default_rng(seed).integers(2 ** 31))
        counts = gm.shots * coates(hist, gm.shots, dead)        # as K linear shots
        # each sample's threshold on the histogram: its armed shots' background counts
        armed = gm.shots - blind_shots(hist, dead)
        ret = find_returns(counts, start, sensor.dt, sensor.sigma,
                           det.level(armed * -np.expm1(-b)), det.max_returns, det.decompose,
                           gm.shots * b, detect=hist)
        ret.amplitude /= gm.shots                               # per shot
        ret.intensity /= gm.shots
        return ret, hist
    measured = waves
    if sensor.noise is not None:
        measured = draw_noise(sensor.noise, waves, sensor.dt, 1, seed)[0] / sensor.noise.gain
    if det.cfar:                       # each record's own background, not the sensor's
        b = cfar_background(measured, 2.0 * sensor.fwhm / sensor.dt)
    level = det.level(b[:, None] if det.cfar else b)
    ret = find_returns(measured, start, sensor.dt, sensor.sigma, level, det.max_returns,
                       det.decompose, b, echoes=echoes if measured is waves else None)
    return ret, measured


def _part_of(scene):
    counts = [len(p.faces) for p in scene.parts]
    return np.repeat(np.arange(len(counts), dtype=np.int32), counts)


def scan(scene, pattern, platform, sensor, *, motions=None, seed=0, keep_waveforms=False,
         waveforms_file=None, chunk_pulses=None, jobs=None, executor=None, progress=False,
         run_dir=None):
    """The point cloud ``sensor``, scanning ``pattern`` from ``platform``, records from
    ``scene`` (module docstring; physics: :mod:`meshladar.scan.cast`).

    Parameters
    ----------
    scene : Scene
        A mesh scene; its coatings weigh every hit.
    pattern : ScanPattern
        When and where each pulse goes (:mod:`meshladar.scan.patterns`).
    platform : Platform
        The sensor's pose against time (:mod:`meshladar.scan.platforms`).
    sensor : ScanSensor
        Transmitter, receiver, noise and detector.
    motions : dict, optional
        ``{part (index or name): meshladar.motion.Motion}``: parts moving rigidly in the
        scan (:mod:`meshladar.scan.moving`: blur, Doppler at the sensor's wavelength).
    seed : int or None
        The noise's seed (default 0): the chunk from pulse k draws from ``[seed, k]`` (a
        run of its records, :data:`RECORD_SAMPLES`, from ``[seed, k, the run's first]``).
    keep_waveforms : bool
        Return every pulse's record (memory: pulses × samples × 8 bytes); with
        ``run_dir`` the sensor's ``samples`` must fix their length.
    waveforms_file : str or os.PathLike, optional
        An HDF5 file every chunk's records stream into (not kept in memory), with the
        points and parameters at the end (:func:`~meshladar.scan.files.read_hdf5`). Not
        with ``keep_waveforms``, ``run_dir`` or ``executor``.
    chunk_pulses : int, optional
        Pulses per chunk (default :data:`CHUNK_RAYS` sub-rays' worth; a flash's: whole frames).
    jobs, executor : optional
        Threads (default: one per core for long scans, as :func:`meshladar.stream.run_chunks`),
        or any executor (a Dask cluster's: :func:`meshladar.stream.dask_executor`).
    progress : bool
        A progress bar over the pulses, on a terminal only (default False).
    run_dir : str or os.PathLike, optional
        A run folder: a scan stopped at any point and run again computes only the chunks
        it lacks, and gives the same points.

    Returns
    -------
    PointCloud
        The returns with their ground truth; ``info`` says the conventions.

    Warns
    -----
    RecordLengthWarning, EmptyScanWarning, MeshladarWarning
        A fixed record cut echoes; no return was recorded (each says why and what helps);
        a Motion's wavelength is not the sensor's.

    Raises
    ------
    ParameterError
        When an argument is of the wrong kind or out of range (waypoints not spanning the
        pulses: :meth:`Platform.check_covers`; a flash array's beam with more set than
        ``tol``: :func:`~meshladar.scan.footprint.check_flash_beam`), before any ray is cast.
    """
    _check(scene, pattern, platform, sensor)
    split, seed = moving_parts(scene, motions), check_seed("seed", seed)
    motions = at_wavelength(motions, sensor.wavelength)          # as recorded
    _check_keep(keep_waveforms, run_dir, sensor)
    foot = _footprint(pattern, sensor)
    per, slots = _chunk_pulses(pattern, chunk_pulses, len(foot[0])), sensor.detector.max_returns
    sink = _sink(waveforms_file, keep_waveforms, run_dir, executor, sensor)
    with sink if sink is not None else contextlib.nullcontext():   # dropped on a failure
        job = ScanJob(scene, pattern, platform, sensor, foot, seed, keep_waveforms, slots,
                      _chunk, split, sink, folder=run_dir is not None,
                      backend=resolve_backend("auto"), part_of=_part_of(scene))
        results = run_chunks(scan_chunk, job, len(pattern), chunk_size=per, unit="pulses",
                             work=float(len(pattern) * len(foot[0])),
                             arrays=chunk_arrays(slots, sensor, keep_waveforms),
                             threads=True, jobs=jobs, executor=executor, progress=progress,
                             run_dir=run_dir, job=_description(job, run_dir, motions))
        points, waves, starts = records(results, slots)
        _warn(results, points, job)
        cloud = PointCloud(points, _info(pattern, platform, sensor, seed, motions), waves, starts)
        if sink is not None:
            sink.finish(cloud)
    return cloud


def _description(job, run_dir, motions):
    """What a run folder's chunks were computed from (None without a folder)."""
    if run_dir is None:
        return None
    return job_description(job.scene, job.pattern, job.platform, job.sensor, job.seed,
                           job.keep, geometry(job.scene, "flat").key, motions)


def _warn(results, points, job):
    """The scan's warnings once its chunks are in: echoes that a fixed record cut, a
    cloud with no return (:func:`_warn_cut`, ``_empty.warn_empty``), and Geiger-mode
    returns piled up to about the most K shots read, ln K events per shot
    (:data:`GEIGER_PILEUP_SHOTS`)."""
    cut = _warn_cut(results, job.sensor, len(job.pattern))
    if not len(points):
        warn_empty(results, job, cut)
    gm = job.sensor.geiger
    if gm is None or gm.shots < GEIGER_PILEUP_SHOTS:
        return
    level = math.log(gm.shots)
    piled = int(np.count_nonzero(points["intensity"] >= level))
    if piled:
        warnings.warn(f"{piled} of {len(points)} Geiger-mode returns read {level:.3g} "
                      f"events per shot or more (ln K, about the most {gm.shots} shots "
                      "read): their pixels fire on the echo's leading edge nearly every "
                      "shot, Coates' correction cannot restore what came after, and they "
                      "range early and read low; lower pulse_energy (or attenuate) toward "
                      "one event per shot, or histogram more shots", MeshladarWarning,
                      stacklevel=user_stacklevel())


def _check_keep(keep, run_dir, sensor):
    if not isinstance(keep, bool):
        raise ParameterError(f"keep_waveforms must be True or False; got {keep!r}")
    if keep and sensor.echoes == "discrete":
        raise ParameterError("keep_waveforms: a sensor with echoes='discrete' makes no "
                             "records; use echoes='waveform'")
    if keep and run_dir is not None and sensor.samples is None:
        raise ParameterError("keep_waveforms with run_dir needs the sensor's samples (a "
                             "fixed record length), so that every chunk's records fit")


def _chunk_pulses(pattern, chunk_pulses, sub_rays):
    """Pulses per chunk: at most :data:`CHUNK_RAYS` sub-rays' worth, the pattern split into
    chunks of equal size (so that threads finish together), or the user's; whole frames of
    a flash array."""
    if chunk_pulses is None:
        per = max(1, CHUNK_RAYS // sub_rays)
        per = -(-len(pattern) // -(-len(pattern) // per))   # equal chunks: threads balance
    else:
        per = check_count("chunk_pulses", chunk_pulses)
    if pattern.is_flash:
        frame = pattern.shape[0] * pattern.shape[1]
        per = max(frame, per // frame * frame)
    return per


def _sink(path, keep, run_dir, executor, sensor):
    """The waveform file a scan streams into, or None; refused with a discrete-return
    ``sensor`` (no records), ``keep_waveforms`` (in memory instead), ``run_dir`` (a
    resumed scan would lack the chunks done before) or an ``executor`` (the file is
    written by this process's threads)."""
    if path is None:
        return None
    if sensor.echoes == "discrete":
        raise ParameterError("waveforms_file: a sensor with echoes='discrete' makes no "
                             "records; use echoes='waveform'")
    if executor is not None:
        raise ParameterError("waveforms_file is written by this process's threads; with an "
                             "executor, use keep_waveforms=True and write_hdf5")
    if keep:
        raise ParameterError("waveforms_file streams the records to disk; keep_waveforms "
                             "keeps them in memory: give one of them")
    if run_dir is not None:
        raise ParameterError("waveforms_file with run_dir: a resumed scan would not write "
                             "the chunks done before; use keep_waveforms=True with run_dir "
                             "(and the sensor's samples), then write_hdf5")
    return WaveformSink(path, geiger=sensor.geiger is not None)
