"""A scan's chunks through :func:`meshladar.stream.run_chunks`: threads, a Dask executor,
a progress bar and resumable run folders, as for sinograms.

A chunk is a run of consecutive pulses; its noise is seeded by ``[seed, first pulse]``, so
the points do not depend on how chunks are scheduled, and a run resumed from its folder
gives the same points as one that was never stopped. Where a run folder keeps the chunks,
a chunk's result is fixed slots, ``max_returns`` per pulse, one array per record field
(``returns`` counts each pulse's), which the folder stores and checks; a false alarm's
truth (nan) is kept as 0 and restored from its face, −1. Without a folder a chunk's
result is its records as they are.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..runs import array_digest
from .points import POINT_DTYPE

__all__ = ["ScanJob", "scan_chunk", "chunk_arrays", "records", "job_description"]

_TRUTH = ("true_range", "true_x", "true_y", "true_z")
#: What a scan's chunk computes, for its run folder: 2 since sub-rays are built from the
#: pulse's turned frame, records in runs, and the platform's time origin is described.
JOB_FORMAT = 2


class ScanJob(NamedTuple):
    """What every chunk needs (sent to each worker once)."""

    scene: object
    pattern: object
    platform: object
    sensor: object
    foot: tuple
    seed: object
    keep: bool
    slots: int
    run: object          # the chunk function: (job, slice, seed) -> (records, blocks of
    #                      (first pulse, waves, starts) or None, needed lengths or None,
    #                      (pulses that met the scene, the most photoelectrons a pulse
    #                      returned before noise) for a chunk without a record, else None)
    split: object        # the moving parts (meshladar.scan.moving.MovingParts) or None
    sink: object = None  # a WaveformSink the chunks stream their records into, or None
    folder: bool = False  # a run folder keeps the chunks: fixed slots, not records
    backend: str = None   # the ray-casting backend, resolved once (None: "auto" per chunk)
    part_of: object = None  # each face's part (int32), made once


def _chunk_seed(seed, first):
    if seed is None:
        return None
    return [seed, first] if isinstance(seed, int) else list(seed) + [first]


def scan_chunk(job, items):
    """One chunk's slots (module docstring), or its records as they are where no run
    folder keeps them: ``job.run`` on the pulses ``items``."""
    lo, hi = int(items[0]), int(items[-1]) + 1
    rec, blocks, needed, lit = job.run(job, slice(lo, hi), _chunk_seed(job.seed, lo))
    out = _slots(rec, lo, hi, job.slots) if job.folder else {"records": rec}
    if lit is not None:                    # for the scan's word on an empty cloud (older
        out["lit"] = np.asarray(lit, float)  # run folders' chunks lack it)
    if needed is not None:                 # the record length each pulse's echoes need
        out["needed"] = needed
    if job.sink is not None and blocks is not None:
        for first, waves, starts in blocks:
            job.sink.write(lo + first, waves, starts)
    elif job.keep and blocks is not None and job.folder:     # a fixed length: one block
        out["waveform"], out["start"] = blocks[0][1], blocks[0][2]
    elif job.keep and blocks is not None:
        out["waveform"] = [b[1] for b in blocks]
        out["start"] = [b[2] for b in blocks]
    return out


def _slots(rec, lo, hi, slots):
    """A chunk's records as ``slots`` fixed slots per pulse, one array per field."""
    n = hi - lo
    local = (rec["pulse_id"] - lo).astype(np.int64)
    slot = rec["return_number"].astype(np.int64) - 1
    out = {"returns": np.bincount(local, minlength=n).astype(np.int64)}
    for name in POINT_DTYPE.names:
        a = np.zeros((n, slots), POINT_DTYPE[name])
        values = rec[name]
        if name in _TRUTH:
            values = np.where(np.isnan(values), 0.0, values)
        a[local, slot] = values
        out[name] = a
    return out


def chunk_arrays(slots, sensor, keep):
    """``{name: trailing shape}`` of a chunk's arrays, for the run folder's checks (a fixed
    record length of waveforms: ``needed``, each pulse's echoes' length). A chunk's ``lit``
    (:func:`scan_chunk`) is one pair a chunk, not a row a pulse: not listed."""
    shapes = {"returns": ()}
    samples = sensor.samples
    if samples is not None and sensor.echoes == "waveform":
        shapes["needed"] = ()
    shapes.update({name: (slots,) for name in POINT_DTYPE.names})
    if keep:
        shapes.update(waveform=(samples,), start=())
    return shapes


def records(results, slots):
    """The records of every chunk, in pulse order then time; and the waveform blocks and
    starts (None when not kept). Chunks that kept their records (no run folder) are joined
    as they are; slots are written field by field into one array made once."""
    waves = "waveform" in results[0] if results else False
    waves = (_blocks(results, "waveform") if waves else None,
             _blocks(results, "start") if waves else None)
    if results and "records" in results[0]:
        # joined as bytes (numpy joins structured arrays field by field, 2-5x slower)
        joined = np.concatenate([np.ascontiguousarray(r["records"]).view(np.uint8)
                                 for r in results])
        return (joined.view(POINT_DTYPE),) + waves
    kept = [np.flatnonzero(np.arange(slots)[None, :] < np.asarray(res["returns"])[:, None])
            for res in results]
    rec = np.empty(sum(len(k) for k in kept), POINT_DTYPE)
    at = 0
    for res, idx in zip(results, kept):
        part = rec[at:at + len(idx)]
        for name in POINT_DTYPE.names:           # every field written: none left unset
            part[name] = np.asarray(res[name]).reshape(-1)[idx]
        at += len(idx)
    noise = rec["true_face"] < 0
    if noise.any():
        for name in _TRUTH:
            rec[name][noise] = np.nan
    return (rec,) + waves


def _blocks(results, name):
    """The chunks' blocks of ``name`` in order (a chunk's one array, or its list of runs)."""
    return tuple(np.asarray(b) for r in results
                 for b in (r[name] if isinstance(r[name], list) else [r[name]]))


def job_description(scene, pattern, platform, sensor, seed, keep, geometry_key, motions):
    """Everything that determines a scan's points, for its run folder (``format``: the
    version of what a chunk computes from them; a folder of another is refused)."""
    return {"kind": "scan", "format": JOB_FORMAT, "geometry": geometry_key,
            "materials": [repr(m) for m in scene.materials],
            "times": array_digest(pattern.times), "directions": array_digest(pattern.directions),
            "channels": array_digest(pattern.channels), "pattern": pattern.describe(),
            "platform": platform.describe(), "sensor": sensor.describe(), "seed": seed,
            "waveforms": keep,
            "motions": {str(k): m.describe() for k, m in (motions or {}).items()}}
