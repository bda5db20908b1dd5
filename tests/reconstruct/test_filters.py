"""fourier_filter's padded length: a positive multiple of 4, where scikit-image's kernel is
the symmetric Ram-Lak kernel; any other length is refused before any work, naming it."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.reconstruct import fourier_filter


def _circular_ram_lak(n):
    """The band-limited Ram-Lak kernel at circular offsets d = min(j, n − j): ¼ at 0,
    −1/(πd)² at odd d, 0 at even d; its FFT is the ramp's frequency response."""
    d = np.minimum(np.arange(n), n - np.arange(n))
    h = np.zeros(n)
    h[0] = 0.25
    h[d % 2 == 1] = -1.0 / (np.pi * d[d % 2 == 1]) ** 2
    return np.real(np.fft.fft(h))


@pytest.mark.parametrize("n", [4, 12, 64, np.int64(128), 1000])
def test_a_multiple_of_four_is_the_symmetric_ram_lak_ramp(n):
    np.testing.assert_allclose(fourier_filter(n), _circular_ram_lak(int(n)), atol=1e-15)
    assert abs(fourier_filter(n)[0]) < 0.05               # a ramp: about 0 at zero frequency


@pytest.mark.parametrize("n", [66, 10, 2, 65, 7, 1, 0, -4, 64.0, True, "64"])
def test_any_other_padded_length_is_refused_naming_it(n):
    # 66 and 10 (2 mod 4) used to return a wrong response (≈ 0.09 at the zero frequency,
    # the kernel asymmetric); odd lengths failed inside numpy on a shape mismatch
    with pytest.raises(ParameterError, match=r"n_padded must be a positive integer multiple "
                       rf"of 4 .*; got {n!r}$"):
        fourier_filter(n, "hann")


def test_a_length_beyond_the_allocation_cap_is_refused_before_allocating():
    with pytest.raises(ParameterError, match=r"n_padded: a filter response of 1099511627776 "
                       r"samples would need .* GiB"):
        fourier_filter(2 ** 40)
