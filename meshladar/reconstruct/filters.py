"""The ramp filters of filtered backprojection, as scikit-image builds them.

The filters and their discretisation are scikit-image's (``skimage.transform.iradon``): the
band-limited Ram-Lak kernel transformed to the frequency domain (Kak & Slaney Eq. 3.61),
times a window (shepp-logan, cosine, hamming, hann), on projections zero-padded to the next
power of two ≥ 2 n_bins (no wrap-around). :func:`~meshladar.reconstruct.fbp2d.fbp` filters
each view's profile with them before backprojecting it.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_choice, check_size, short
from ..errors import ParameterError

__all__ = ["fourier_filter", "FILTERS"]

#: Filter windows, scikit-image's names.
FILTERS = ("ramp", "shepp-logan", "cosine", "hamming", "hann")


def fourier_filter(n_padded, filter="ramp"):
    """The frequency response (n_padded,) of a filter, as scikit-image builds it.

    The ramp is the FFT of the band-limited Ram-Lak kernel h[0] = ¼, h[odd n] = −1/(πn)²,
    which is |ν| (cycles per sample) up to its truncation; windows multiply it. Returned
    without scikit-image's extra factor 2 (it pairs with a 180° scan).

    Parameters
    ----------
    n_padded : int
        Length of the zero-padded projection the response multiplies: a positive multiple
        of 4 (the kernel's construction is symmetric, hence right, only there; any other
        length is refused). :func:`fbp` passes a power of two, at least 64 and at least
        2 n_bins.
    filter : {"ramp", "shepp-logan", "cosine", "hamming", "hann"}, default "ramp"
        The window (:data:`FILTERS`) applied to the ramp: "shepp-logan" multiplies by
        sin(ω)/ω with ω = π ν (ν from ``scipy.fft.fftfreq``; the zero frequency is left
        as is), "cosine" by a half sine period, "hamming" and "hann" by numpy's windows,
        each shifted into FFT order.

    Returns
    -------
    (n_padded,) ndarray of float64
        The real part of the kernel's FFT times the window, in FFT order (index 0 is
        the zero frequency, as ``scipy.fft.fftfreq``): the factor by which a padded
        profile's spectrum is multiplied, ≈ |ν| with ν in cycles per sample for the
        ramp (0.497 at the Nyquist frequency ½ for n_padded = 64).

    Raises
    ------
    ParameterError
        When ``filter`` is not one of :data:`FILTERS`, or ``n_padded`` is not a positive
        integer multiple of 4 (or its response would exceed the allocation cap).

    References
    ----------
    A. C. Kak and M. Slaney, *Principles of Computerized Tomographic Imaging*, IEEE Press
    (1988), Ch. 3, Eq. (61) (the band-limited Ram-Lak kernel); scikit-image's
    ``skimage.transform.iradon`` (its filters and discretisation).
    """
    from scipy import fft as sfft       # scipy.fft: only where it is used (startup)

    check_choice("filter", filter, FILTERS)
    n_padded = _check_length(n_padded)
    n = np.concatenate((np.arange(1, n_padded / 2 + 1, 2, dtype=int),
                        np.arange(n_padded / 2 - 1, 0, -2, dtype=int)))
    f = np.zeros(n_padded)
    f[0] = 0.25
    f[1::2] = -1.0 / (np.pi * n) ** 2
    response = np.real(sfft.fft(f))
    if filter == "shepp-logan":
        omega = np.pi * sfft.fftfreq(n_padded)[1:]
        response[1:] *= np.sin(omega) / omega
    elif filter == "cosine":
        response *= sfft.fftshift(np.sin(np.linspace(0, np.pi, n_padded, endpoint=False)))
    elif filter == "hamming":
        response *= sfft.fftshift(np.hamming(n_padded))
    elif filter == "hann":
        response *= sfft.fftshift(np.hanning(n_padded))
    return response


def _check_length(n_padded):
    """Refuse a padded length other than a positive multiple of 4: scikit-image's kernel
    puts −1/(πn)² at the odd offsets counted from both ends, which is the symmetric
    (circular) Ram-Lak kernel only when the length is a multiple of 4; at 2 mod 4 its
    response is silently wrong (≈ 0.09 at the zero frequency instead of ≈ 0) and at an
    odd length numpy fails on a shape mismatch. Returns it as an int."""
    if (isinstance(n_padded, (bool, np.bool_)) or not isinstance(n_padded, (int, np.integer))
            or n_padded < 4 or n_padded % 4):
        raise ParameterError(f"n_padded must be a positive integer multiple of 4 (fbp pads to "
                             f"a power of two >= 64); got {short(n_padded)}")
    n_padded = int(n_padded)
    count = n_padded if n_padded < 2 ** 1000 else math.inf     # float() would overflow
    check_size("n_padded", count, 8 * 4, f"a filter response of {short(n_padded)} samples",
               "ask for a shorter length")
    return n_padded


def _filtered(values, filter):
    """Each view's profile filtered with :func:`fourier_filter`, zero-padded to a power of
    two >= 2 n_bins (no wrap-around), as scikit-image."""
    from scipy import fft as sfft       # scipy.fft: only where it is used (startup)

    n = values.shape[1]
    n_pad = max(64, int(2 ** math.ceil(math.log2(2 * n))))
    response = fourier_filter(n_pad, filter)
    # full complex FFT: the windows are not exactly symmetric (scikit-image keeps the real part)
    spectrum = sfft.fft(values, n=n_pad, axis=1)
    return np.ascontiguousarray(np.real(sfft.ifft(spectrum * response, axis=1))[:, :n])
