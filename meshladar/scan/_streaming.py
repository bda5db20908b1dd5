"""A scan's chunks through :func:`meshladar.stream.run_chunks`: threads, a Dask executor,
a progress bar and resumable run folders, as for sinograms.

A chunk is a run of consecutive pulses; its noise is seeded by ``[seed, first pulse]``, so
the points do not depend on how chunks are scheduled, and a run resumed from its folder
gives the same points as one that was never stopped. A chunk's result is kept as fixed
slots, ``max_returns`` per pulse, one array per record field (``returns`` counts each
pulse's), which the run folder stores and checks; a false alarm's truth (nan) is kept as
0 and restored from its face, −1.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..runs import array_digest
from .points import POINT_DTYPE

__all__ = ["ScanJob", "scan_chunk", "chunk_arrays", "records", "job_description"]

_TRUTH = ("true_range", "true_x", "true_y", "true_z")


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
    run: object          # the chunk function: (job, slice, seed) -> (records, waves, starts)
    split: object        # the moving parts (meshladar.scan.moving.MovingParts) or None
    sink: object = None  # a WaveformSink the chunks stream their records into, or None


def _chunk_seed(seed, first):
    if seed is None:
        return None
    return [seed, first] if isinstance(seed, int) else list(seed) + [first]


def scan_chunk(job, items):
    """One chunk's slots (module docstring): ``job.run`` on the pulses ``items``."""
    lo, hi = int(items[0]), int(items[-1]) + 1
    rec, waves, starts = job.run(job, slice(lo, hi), _chunk_seed(job.seed, lo))
    n = hi - lo
    local = (rec["pulse_id"] - lo).astype(np.int64)
    slot = rec["return_number"].astype(np.int64) - 1
    out = {"returns": np.bincount(local, minlength=n).astype(np.int64)}
    for name in POINT_DTYPE.names:
        a = np.zeros((n, job.slots), POINT_DTYPE[name])
        values = rec[name]
        if name in _TRUTH:
            values = np.where(np.isnan(values), 0.0, values)
        a[local, slot] = values
        out[name] = a
    if job.sink is not None and waves is not None:
        job.sink.write(lo, waves, starts)
    elif job.keep and waves is not None:
        out["waveform"], out["start"] = waves, starts
    return out


def chunk_arrays(slots, samples, keep):
    """``{name: trailing shape}`` of a chunk's arrays, for the run folder's checks."""
    shapes = {"returns": ()}
    shapes.update({name: (slots,) for name in POINT_DTYPE.names})
    if keep:
        shapes.update(waveform=(samples,), start=())
    return shapes


def records(results, slots):
    """The records of every chunk's slots, in pulse order then time; and the waveform
    blocks and starts (None when not kept). Written field by field into one array made
    once (a chunk's records joined after being made each in a zeroed array took 2.5x as
    long)."""
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
    waves = "waveform" in results[0] if results else False
    return (rec, tuple(np.asarray(r["waveform"]) for r in results) if waves else None,
            tuple(np.asarray(r["start"]) for r in results) if waves else None)


def job_description(scene, pattern, platform, sensor, seed, keep, geometry_key, motions):
    """Everything that determines a scan's points, for its run folder."""
    return {"kind": "scan", "geometry": geometry_key,
            "materials": [repr(m) for m in scene.materials],
            "times": array_digest(pattern.times), "directions": array_digest(pattern.directions),
            "channels": array_digest(pattern.channels), "pattern": pattern.describe(),
            "platform": platform.describe(), "sensor": sensor.describe(), "seed": seed,
            "waveforms": keep,
            "motions": {str(k): m.describe() for k, m in (motions or {}).items()}}
