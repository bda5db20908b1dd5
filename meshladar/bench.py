"""Benchmarks: medians of several runs in one process (``meshladar bench``).

Speed is measured here, never in timed tests. Each case is run ``repeats`` times after one
warm-up run, and the median, minimum and maximum wall times are reported.
"""

from __future__ import annotations

import statistics
import time

__all__ = ["time_call", "bench_analytic"]


def time_call(fn, *, repeats=5):
    """Wall times (s) of ``repeats`` calls of ``fn()`` after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def bench_analytic(*, repeats=5):
    """The paper's analytic sinograms (360 views × 512 bins of A/256): one row per case.

    Returns a list of dicts with ``case``, ``median_s``, ``min_s``, ``max_s``.
    """
    from . import forward, materials
    from .ladar import Ladar
    from .scene import Disk, Ellipse, Scene

    gray, al = materials.DARK_GRAY, materials.ALUMINUM
    ladar = Ladar.paper()

    def pair(big, small):
        return Scene([Disk((-0.3, 0.0), 0.4, big, name="large"),
                      Disk((0.4, 0.0), 0.3, small, name="small")])

    cases = {
        "disk pair, gray + gray": pair(gray, gray),
        "disk pair, aluminium + aluminium": pair(al, al),
        "disk pair, gray + aluminium": pair(gray, al),
        "disk pair, aluminium + gray": pair(al, gray),
        "ellipse A=0.6 B=0.3, aluminium": Scene([Ellipse((0.0, 0.0), (0.6, 0.3), 0.0, al)]),
        "disk A=0.8, aluminium (one profile)": Scene([Disk((0.0, 0.0), 0.8, al)]),
    }
    rows = []
    for name, scene in cases.items():
        t = time_call(lambda s=scene: forward.simulate(s, ladar), repeats=repeats)
        rows.append({"case": name, "median_s": statistics.median(t), "min_s": min(t),
                     "max_s": max(t)})
    return rows
