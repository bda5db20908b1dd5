"""The scan benchmark runs at a small size and reports rates that a cast-then-process
pipeline can give: the scan below the bare cast of its own sub-rays, every rate finite."""

from __future__ import annotations

import math

import pytest

from meshladar.studies.bench_scan import bench_scan


@pytest.mark.slow
def test_the_scan_benchmark_reports_the_scan_below_its_own_cast():
    r = bench_scan(subdivisions=3, duration=0.01, rounds=1)
    assert r["faces"] == 1280 and r["sub_rays"] == 3000 * 16
    assert 0 < r["scan_over_cast"] < r["discrete_over_cast"] < 1
    assert all(math.isfinite(r[k]) and r[k] > 0 for k in
               ("packet_mrays", "scan_mrays", "discrete_mrays", "two_over_one",
                "cast_two_over_one", "flash_fps"))
