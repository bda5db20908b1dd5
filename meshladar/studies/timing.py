"""Timing helpers of the benchmarks: medians of several runs in one process, and the
icosphere the mesh benchmarks trace."""

from __future__ import annotations

import statistics
import time

from ..meshes import sphere
from ..scene import Scene

__all__ = ["time_call", "interleaved", "interleaved_times", "icosphere_scene"]


def time_call(fn, *, repeats=5):
    """Wall times (s) of ``repeats`` calls of ``fn()`` after one warm-up call.

    Parameters
    ----------
    fn : callable
        Called with no arguments; what it returns is discarded.
    repeats : int, keyword-only
        Timed calls (default 5).

    Returns
    -------
    list of float
        Each timed call's wall time in seconds (``time.perf_counter``), in order; the
        warm-up call is not included.
    """
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def interleaved(fns, *, repeats=3):
    """Median wall time (s) of each of ``fns`` (a dict of name → callable), run in rounds
    (one call of each per round, after one warm-up round) so that a shared machine's load
    falls on all of them alike.

    Parameters
    ----------
    fns : dict of str to callable
        The calls to time, by name; each is called with no arguments.
    repeats : int, keyword-only
        Timed rounds after the warm-up round (default 3); at least 1 (the median of no
        times fails).

    Returns
    -------
    dict of str to float
        Each name's median wall time in seconds.
    """
    times = interleaved_times(fns, repeats=repeats)
    return {k: statistics.median(v) for k, v in times.items()}


def interleaved_times(fns, *, repeats=3, clock=time.perf_counter, warm_up=True):
    """Every timed call of each of ``fns``, run in rounds as :func:`interleaved` (one call
    of each per round, after one warm-up round unless ``warm_up`` is False: the caller
    warmed them up), by ``clock``.

    Parameters
    ----------
    fns : dict of str to callable
        The calls to time, by name; each is called with no arguments.
    repeats : int, keyword-only
        Timed rounds after the warm-up round (default 3).
    clock : callable, keyword-only
        Returns the time in seconds: ``time.perf_counter`` (wall, the default) or
        ``time.process_time`` (the CPU seconds of this process, all its threads: on a
        loaded machine, what one-thread code costs regardless of what else runs).
    warm_up : bool, keyword-only
        Call each once, untimed, before the rounds (default True).

    Returns
    -------
    dict of str to list of float
        Each name's times in seconds, round by round (round r of every name is entry r).
    """
    for fn in fns.values() if warm_up else ():
        fn()
    times = {k: [] for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            t0 = clock()
            fn()
            times[k].append(clock() - t0)
    return times


def icosphere_scene(subdivisions, material):
    """A one-part scene: a sphere of radius 0.5 at the origin, ``subdivisions`` times
    subdivided (6: 81,920 faces), in ``material``.

    Parameters
    ----------
    subdivisions : int
        Icosphere subdivisions, ≥ 0: 20 × 4^``subdivisions`` faces.
    material : BRDF
        The coating of every face (e.g. :data:`meshladar.materials.DARK_GRAY`).

    Returns
    -------
    Scene
        A mesh scene of one part (:func:`meshladar.meshes.sphere`, with its exact
        normals).
    """
    return Scene.from_parts([sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=subdivisions)],
                             [material])
