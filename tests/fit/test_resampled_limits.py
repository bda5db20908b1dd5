"""CoatingKernel.resampled refuses a sample count beyond its cap before building anything:
an analytic kernel's pieces grow linearly with it (2^23 on one view took 3 GB), and a mesh
kernel's count is named as the argument the user gave."""

from __future__ import annotations

import pytest

from meshladar.brdf import SandfordRobertson
from meshladar.errors import ParameterError
from meshladar.fit import coating_kernel
from meshladar.fit import kernels as kernels_module
from meshladar.fit.kernels import MAX_KERNEL_SAMPLES
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk

SCENE = Scene([Disk((0.1, 0.0), 0.5, SandfordRobertson(0.1, 0.4, 0.2, 0.02), name="disk")])
LAD = Ladar.paper(angles_deg=[0.0])


def _refuse_to_build(*args, **kwargs):
    raise AssertionError("the kernel was built before samples was checked")


@pytest.mark.parametrize("samples", [2 * MAX_KERNEL_SAMPLES + 1, 10**9, 10**30])
def test_an_analytic_kernel_refuses_samples_beyond_twice_the_cap_before_building(
        monkeypatch, samples):
    kernel = coating_kernel(SCENE, LAD, samples=64)
    monkeypatch.setattr(kernels_module, "analytic_fields", _refuse_to_build)
    with pytest.raises(ParameterError, match=rf"^samples must be an integer in \[1, "
                       rf"{2 * MAX_KERNEL_SAMPLES}\]; got {samples}$"):
        kernel.resampled(samples)


def test_an_analytic_kernel_takes_twice_the_cap_the_fits_finer_kernel(monkeypatch):
    """A fit checks a kernel of N pieces against 2N, so the largest coating_kernel builds
    (MAX_KERNEL_SAMPLES) must still resample to twice that."""
    kernel = coating_kernel(SCENE, LAD, samples=64)
    monkeypatch.setattr(kernels_module, "analytic_fields", _refuse_to_build)
    with pytest.raises(AssertionError, match="the kernel was built"):
        kernel.resampled(2 * MAX_KERNEL_SAMPLES)


@pytest.mark.parametrize("samples, message", [
    (1e7, r"^samples must be in \[1e-300, 1e\+06\]; got 10000000\.0$"),
    (0.0, r"^samples must be in \[1e-300, 1e\+06\]; got 0\.0$"),
])
def test_a_mesh_kernel_names_samples_when_it_is_out_of_range(samples, message):
    kernel = coating_kernel(SCENE.tessellate(64), LAD, samples=4)
    with pytest.raises(ParameterError, match=message):
        kernel.resampled(samples)
