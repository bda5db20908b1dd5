"""The bounce benchmark runs at a small size: a cap of a quarter of the sphere, every rate
finite and positive, the paths counted as asked."""

from __future__ import annotations

import math

from meshladar.studies.bench import bounce_line
from meshladar.studies.bench_bounces import bench_bounces


def test_the_bounce_benchmark_reports_finite_rates(monkeypatch):
    r = bench_bounces(subdivisions=3, views=2, samples=1 << 10, rounds=1)
    assert r["paths"] == 2 * 1024 and 0 < r["faces"] < 1280 // 3
    assert all(math.isfinite(r[k]) and r[k] > 0 for k in
               ("one_thread", "two_threads", "packets_over_embreex", "auto_over_one"))
    import meshladar.studies.bench as bench
    monkeypatch.setattr(bench, "bench_bounces", lambda: r)
    assert bounce_line().startswith(f"bounces, {r['faces']}-triangle bowl")
