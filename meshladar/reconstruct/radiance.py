"""The paper's preprocessing of binned radiance before reconstruction, against glints.

A glint's few bright bins can hide a reconstruction's diffuse parts. Jin & Levine (2009,
Sec. 4.B) reconstruct instead from the logarithm of the radiance above a floor
(:func:`log_radiance`, Fig. 11a) or from the radiance clipped at a small fraction of its
maximum (:func:`clip_radiance`, Fig. 11b); :func:`noise_floor` is the data's noise level
relative to its maximum, a floor for the log that keeps the noise out. Each transform
records itself in the sinogram's ``info["preprocess"]``, in order.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._validate import check_real, check_sinogram
from ..sinogram import Sinogram

__all__ = ["log_radiance", "clip_radiance", "noise_floor", "LOG_FLOOR", "PAPER_CLIP"]

#: Default floor of :func:`log_radiance`, as a fraction of the sinogram's maximum.
LOG_FLOOR = 1e-6
#: The paper's clipping threshold, as a fraction of the maximum (Fig. 11b).
PAPER_CLIP = 0.008

#: float64's smallest normal number: a floor, or a floor times the maximum, below it is
#: taken on ratios to the maximum (no underflow to 0, no 1 / floor overflow).
_TINY = float(np.finfo(np.float64).tiny)


def _preprocessed(sinogram, step):
    """The sinogram's info with ``step`` added to its record of preprocessing, in order."""
    before = sinogram.info.get("preprocess")
    return dict(sinogram.info, preprocess=step if not before else f"{before}, then {step}")


def noise_floor(sino, *, quanta=3.0):
    """The data's noise floor relative to its maximum, and at least
    :data:`~meshladar.reconstruct.LOG_FLOOR`: ``quanta`` quanta when the bins are whole
    multiples of a quantum (counted photoelectrons, however scaled), else five robust
    standard deviations of the bins (most bins hold no surface, so their median absolute
    deviation is the noise).

    The bins count as quantised when the smallest non-zero |value| (the quantum) is below
    the peak and more than 99 % of the non-zero bins lie within 1e-6 of a whole multiple
    of it; the robust standard deviation is 1.4826 × the median absolute deviation of all
    the bins, empty ones included.

    Parameters
    ----------
    sino : Sinogram
        The data (anything with a ``values`` array; not checked).
    quanta : float, keyword-only, default 3.0
        The floor in quanta, for quantised data. Not checked.

    Returns
    -------
    float
        The floor as a fraction of the largest |value|, in [:data:`LOG_FLOOR`, 0.5] (it is
        capped at 0.5); :data:`LOG_FLOOR` when every bin is 0.
    """
    v = sino.values
    peak = float(np.abs(v).max(initial=0.0))
    if peak == 0:
        return LOG_FLOOR
    nonzero = np.abs(v[v != 0])
    quantum = float(nonzero.min())
    steps = nonzero / quantum
    if quantum < peak and np.mean(np.abs(steps - np.round(steps)) < 1e-6) > 0.99:
        level = quanta * quantum
    else:
        level = 5.0 * 1.4826 * float(np.median(np.abs(v - np.median(v))))
    return float(min(0.5, max(LOG_FLOOR, level / peak)))


def log_radiance(sinogram: Sinogram, *, floor=LOG_FLOOR) -> Sinogram:
    """The paper's Fig. 11(a) input: the logarithm of the binned radiance.

    ``values → log(max(values, m) / m)`` with m = floor × max(values): bins at or below the
    floor (empty bins included) map to 0, everything else to its log-ratio to the floor, so
    the result is ≥ 0 and finite. A floor of 1e-6 keeps six decades of dynamic range.
    A sinogram whose maximum is ≤ 0 maps to all zeros.

    Parameters
    ----------
    sinogram : Sinogram
        The binned radiance (any radiometry or units).
    floor : float in (0, 1], keyword-only, default :data:`LOG_FLOOR` (1e-6)
        The floor m as a fraction of the sinogram's maximum.

    Returns
    -------
    Sinogram
        Same views and bins, values (n_views, n_bins) ≥ 0 the natural log of the ratio to
        the floor; ``units`` "dimensionless (natural log of the ratio to the floor)" and
        ``info["preprocess"]`` extended with ``"log(floor=...)"``.

    Raises
    ------
    ParameterError
        When ``sinogram`` is not a :class:`~meshladar.Sinogram`, or ``floor`` is not a
        finite real in (0, 1].

    References
    ----------
    Jin & Levine (2009), Sec. 4.B, Fig. 11(a) (the logarithm of the binned radiance as
    the reconstruction's input).

    Examples
    --------
    >>> import meshladar as ml
    >>> pair = ml.phantoms.scene("disk_pair", large=ml.materials.DARK_GRAY,
    ...                          small=ml.materials.ALUMINUM)
    >>> logged = ml.log_radiance(ml.simulate(pair, ml.Ladar.paper(angles_deg=[0.0, 90.0])))
    >>> round(float(logged.values.max()), 4)     # the brightest bin: ln(1 / 1e-6)
    13.8155
    """
    check_sinogram("sinogram", sinogram)
    floor = check_real("floor", floor, low=0.0, high=1.0, low_open=True)
    vmax = float(sinogram.values.max(initial=0.0))
    if vmax <= 0:
        out = np.zeros_like(sinogram.values)
    elif min(floor, floor * vmax) >= _TINY:
        m = floor * vmax
        out = np.log(np.maximum(sinogram.values, m) / m)
    else:       # m or 1 / floor beyond float64's normal range: the same on ratios to vmax
        out = np.log(np.maximum(sinogram.values / vmax, floor)) - math.log(floor)
    info = _preprocessed(sinogram, f"log(floor={floor:g})")
    info["units"] = "dimensionless (natural log of the ratio to the floor)"
    return dataclasses.replace(sinogram, values=out, info=info)


def clip_radiance(sinogram: Sinogram, *, threshold=PAPER_CLIP) -> Sinogram:
    """The paper's Fig. 11(b) input: radiance clipped at ``threshold`` × its maximum.

    Parameters
    ----------
    sinogram : Sinogram
        The binned radiance.
    threshold : float in (0, 1], keyword-only, default :data:`PAPER_CLIP` (0.008)
        The cap as a fraction of the sinogram's maximum value.

    Returns
    -------
    Sinogram
        Same views, bins and units, each value replaced by min(value, threshold ×
        maximum); ``info["preprocess"]`` extended with ``"clip(threshold=...)"``.

    Raises
    ------
    ParameterError
        When ``sinogram`` is not a :class:`~meshladar.Sinogram`, or ``threshold`` is not a
        finite real in (0, 1].

    References
    ----------
    Jin & Levine (2009), Sec. 4.B, Fig. 11(b) (radiance clipped at 0.008 times the
    maximum to remove glints).

    Examples
    --------
    >>> import meshladar as ml
    >>> pair = ml.phantoms.scene("disk_pair", large=ml.materials.DARK_GRAY,
    ...                          small=ml.materials.ALUMINUM)
    >>> sino = ml.simulate(pair, ml.Ladar.paper(angles_deg=[0.0, 90.0]))
    >>> clipped = ml.clip_radiance(sino)            # the paper's 0.008 x the maximum
    >>> float(clipped.values.max() / sino.values.max())
    0.008
    """
    check_sinogram("sinogram", sinogram)
    threshold = check_real("threshold", threshold, low=0.0, high=1.0, low_open=True)
    cap = threshold * float(sinogram.values.max(initial=0.0))
    return dataclasses.replace(sinogram, values=np.minimum(sinogram.values, cap),
                               info=_preprocessed(sinogram, f"clip(threshold={threshold:g})"))
