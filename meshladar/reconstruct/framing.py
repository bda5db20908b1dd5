"""Where a sinogram's target lies, read from its returns alone: for views about z a point
(x, y) ranges −(x cos φ + y sin φ), so the middle of each view's returns traces a sinusoid
whose amplitude and phase are the target's centre (:func:`target_frame`); and the warning
of a default image square that holds the target small and off-centre
(:func:`check_frame`), with the ``center`` and ``extent`` that frame it.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import MeshladarWarning, user_stacklevel

__all__ = ["target_frame", "check_frame", "SMALL_SHARE", "SUPPORT_SHARE", "FRAME_MARGIN"]

#: A target whose frame is narrower than this share of the image's width is warned of.
SMALL_SHARE = 0.1
#: A view's returns: its bins above this share of its brightest bin.
SUPPORT_SHARE = 1e-6
#: The frame's half-width over the target's largest depth in any view.
FRAME_MARGIN = 1.5
#: The fit's smallest singular value over its largest below which the views cannot tell
#: the centre (views over a narrow arc).
_CONDITION = 1e-3


def target_frame(sinogram):
    """The target's centre and a half-width that holds it, from a sinogram of views
    about z: the middle of each view's returns (its first to its last bin above
    :data:`SUPPORT_SHARE` of its brightest) fitted by −(c_x cos φ + c_y sin φ) + d (d: the
    lit side's offset toward the ladar), the half-width :data:`FRAME_MARGIN` × the larger
    of the returns' largest depth in any view and 2|d| (a mirror's glint is one point of
    its surface, |d| in front of the centre: its returns have no depth).

    Parameters
    ----------
    sinogram : Sinogram
        Views about the z axis.

    Returns
    -------
    tuple or None
        ((c_x, c_y), half-width) in scene units, or None where fewer than three views
        return anything or their angles cannot tell the centre.
    """
    values = np.asarray(sinogram.values, np.float64)
    peak = values.max(axis=1, keepdims=True)
    lit = (values > SUPPORT_SHARE * peak) & (peak > 0)
    seen = lit.any(axis=1)
    if seen.sum() < 3:
        return None
    edges = np.asarray(sinogram.bin_edges, np.float64)
    first = np.argmax(lit, axis=1)
    last = lit.shape[1] - 1 - np.argmax(lit[:, ::-1], axis=1)
    lo, hi = edges[first][seen], edges[last + 1][seen]
    phi = np.radians(np.asarray(sinogram.angles_deg, np.float64)[seen])
    a = np.stack([-np.cos(phi), -np.sin(phi), np.ones_like(phi)], axis=1)
    fit, _, _, s = np.linalg.lstsq(a, 0.5 * (lo + hi), rcond=None)
    if s[-1] < _CONDITION * s[0]:
        return None
    size = max(float(np.max(hi - lo)), 2.0 * abs(float(fit[2])))
    return (float(fit[0]), float(fit[1])), FRAME_MARGIN * size


def check_frame(sinogram, extent, center=(0.0, 0.0)):
    """Warn when the image square of half-width ``extent`` about ``center`` holds the
    sinogram's target (:func:`target_frame`) at less than :data:`SMALL_SHARE` of its
    width, naming the ``center`` and ``extent`` that frame it.

    Parameters
    ----------
    sinogram : Sinogram
        Views about the z axis.
    extent : float
        The image's half-width.
    center : (2,) array_like
        The image's centre.
    """
    frame = target_frame(sinogram)
    if frame is None:
        return
    (cx, cy), half = frame
    if half >= SMALL_SHARE * extent:
        return
    off = float(np.hypot(cx - center[0], cy - center[1]))
    width = float(np.max(np.diff(sinogram.bin_edges)))
    warnings.warn(f"the target fills about {100 * half / extent:.2g} % of the image's width "
                  f"(its centre about ({cx:.6g}, {cy:.6g}), {off:.3g} from the image's, read "
                  f"from the sinogram's returns): center=({cx:.6g}, {cy:.6g}) and "
                  f"extent={half:.3g} frame it; its detail is that of the bins, "
                  f"{width:.3g} wide (a target centred on the origin before simulating gets "
                  "finer ones)", MeshladarWarning, stacklevel=user_stacklevel())
