"""Filtered backprojection of reflective sinograms.

``fbp`` treats ``values / bin_width`` as the Radon transform of an image along iso-range
lines and inverts it over the full circle of views:

    f(x) = ½ ∫₀^{2π} (p_φ ∗ h)(r(x)) dφ,   r(x) = −x·w(φ),   ĥ(ν) = |ν| (windowed),

so that the FBP of an exact Radon transform returns the function itself (a uniform disk of
value 1 reconstructs to 1 inside). Reflective data is not symmetric under φ → φ + 180° (the
ladar sees the other side), so views must cover the full circle; each view is weighted by
half its share of the circle.

The filters and their discretisation are scikit-image's (``skimage.transform.iradon``): the
band-limited Ram-Lak kernel transformed to the frequency domain (A. C. Kak and M. Slaney,
*Principles of Computerized Tomographic Imaging*, IEEE Press, 1988, Ch. 3, Eq. 61),
times a window (shepp-logan, cosine, hamming, hann), on projections zero-padded to the next
power of two ≥ 2 n_bins (no wrap-around). With bins of unit width, views 180° − φ, and
pixel centres on skimage's grid, ``fbp`` equals iradon's output for 360° data.

Images (:class:`meshladar.images.Image`): ``image[i, j]`` is the value at (x_j, y_i), pixel
centres c + (−extent + (k + ½) 2 extent/size) increasing along both axes. By default the
square is centred on the origin (the axis the views turn about) with half-width the bins'
reach max(|r_0|, |r_n|) (:func:`bins_reach`): every point whose range falls in the bins in
some view lies in it, so nothing the data holds is cropped, whatever the scene's units.

A target that default square holds small is warned of (:mod:`.framing`). The paper's glint
preprocessing (:mod:`.radiance`) and the filters (:mod:`.filters`) import from here too.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from .._lazy import deferred_module
from .._validate import (check_choice, check_count, check_real, check_sinogram, check_size,
                         finite_array)
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..images import Image, pixel_centres
from ..precision import ANGLE_TOL_DEG, COUNT_SLACK
from ..precision import UNIFORM_RTOL as _UNIFORM_RTOL
from ..sinogram import Sinogram
from .filters import FILTERS, _filtered, fourier_filter
from .framing import check_frame
from .radiance import LOG_FLOOR, PAPER_CLIP, clip_radiance, log_radiance, noise_floor

# compiled loops, imported (with numba) at their first use: a small run loads neither
_folded = deferred_module("meshladar.reconstruct._folded")

__all__ = ["Image", "fbp", "bins_reach", "default_extent", "fourier_filter", "log_radiance",
           "clip_radiance", "resample_uniform", "noise_floor", "quiet_fbp", "FILTERS",
           "INTERPOLATIONS", "LOG_FLOOR", "PAPER_CLIP"]

#: Interpolation of filtered projections at each pixel's range.
INTERPOLATIONS = ("linear", "nearest")
#: A gap between consecutive distinct view angles wider than this many times their median
#: spacing warns that the views do not cover the circle.
_GAP_FACTOR = 3.0
#: FBP samples the angles fully with about π/2 views per bin across the target's returns
#: (π·bins_across/views ≲ 1). Measured on the disk phantom, streaks away from the disk as a
#: fraction of the image's peak: 0.2 % at a ratio of 0.3, 1.4–2.8 % at 0.75, 7 % at 3 (the
#: paper's 350 bins across, 360 views), 18 % at 6. Beyond this ratio (streaks ≥ ¼ peak) it warns.
_UNDERSAMPLED_RATIO = 8.0


def resample_uniform(sino: Sinogram, n_bins=None) -> Sinogram:
    """Resample a sinogram with non-uniform bins onto uniform ones, conserving every view's
    integral over each new bin (linear interpolation of the cumulative integral).

    Parameters
    ----------
    sino : Sinogram
        The data, any strictly increasing bins.
    n_bins : int >= 1, optional
        Number of uniform bins over the same span [r_0, r_n]. Default: the span over the
        narrowest bin's width, rounded up (so no new bin is wider than the narrowest old
        one).

    Returns
    -------
    Sinogram
        Same views, fields and ``info`` (plus ``info["resampled_from"]``, the old number of
        bins), with ``n_bins + 1`` evenly spaced edges from r_0 to r_n and values
        (n_views, n_bins) the bin integrals of each view over the new bins.

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`, ``n_bins`` is not an integer
        >= 1, or the resampling's arrays (24 bytes per view and bin) would pass meshladar's
        4 GiB allocation limit.
    """
    check_sinogram("sino", sino)
    edges = sino.bin_edges
    span = edges[-1] - edges[0]
    if n_bins is None:
        n_bins = int(math.ceil(span / np.min(np.diff(edges)) - COUNT_SLACK))
    n_bins = check_count("n_bins", n_bins)
    check_size("n_bins", float(n_bins) * sino.n_views, 8 * 3,
               f"{sino.n_views} views x {n_bins} bins", "use fewer bins")
    new = np.linspace(edges[0], edges[-1], int(n_bins) + 1)
    cum = np.concatenate([np.zeros((sino.n_views, 1)), np.cumsum(sino.values, axis=1)], axis=1)
    cum_new = np.stack([np.interp(new, edges, row) for row in cum])
    return dataclasses.replace(sino, values=np.diff(cum_new, axis=1), bin_edges=new,
                               info=dict(sino.info, resampled_from=sino.n_bins))


def _distinct_angles(angles_deg):
    """(distinct, index): the distinct view angles (radians in [0, 2π), sorted) and each
    view's index into them. Angles (mod 360°) within ANGLE_TOL_DEG (1e-6°) of a neighbour's
    are one (chained: sorted angles each within it of the next; 0° and 360° included)."""
    a = np.mod(np.deg2rad(np.asarray(angles_deg, dtype=np.float64)), 2 * math.pi)
    order = np.argsort(a, kind="stable")
    s = a[order]
    tol = math.radians(ANGLE_TOL_DEG)
    new = np.concatenate([[True], np.diff(s) > tol])
    group = np.cumsum(new) - 1
    if group[-1] > 0 and s[0] + 2 * math.pi - s[-1] <= tol:      # across 0°: one angle
        new[np.flatnonzero(new)[-1]] = False
        group[group == group[-1]] = 0
    index = np.empty(a.size, dtype=np.intp)
    index[order] = group
    return s[new], index


def _view_weights(angles_deg):
    """Half of each view's share of the circle: the trapezoid on the distinct angles
    (sorted, wrapped; :func:`_distinct_angles`), each angle's share split evenly among the
    views taken at it. Warns for one view, or for a gap between distinct angles wider than
    :data:`_GAP_FACTOR` times their median spacing."""
    if np.size(angles_deg) == 1:
        warnings.warn("one view does not cover the circle: reflective FBP assumes views all "
                      "around the scene; the image is that view's backprojection, streaks "
                      "along its iso-range lines", MeshladarWarning, stacklevel=user_stacklevel())
        return np.array([math.pi])
    s, index = _distinct_angles(angles_deg)
    gaps = np.diff(np.concatenate([s, [s[0] + 2 * math.pi]]))     # gap after each angle
    share = 0.5 * (gaps + np.roll(gaps, 1))
    w = 0.5 * share[index] / np.bincount(index)[index]
    med = float(np.median(gaps))
    if gaps.max() > _GAP_FACTOR * med:
        warnings.warn(
            f"views do not cover the full circle: largest gap {math.degrees(gaps.max()):.3g}° "
            f"vs median spacing {math.degrees(med):.3g}° (of {s.size} distinct angles); "
            "reflective FBP assumes views all around the scene, and the missing ones will "
            "streak the image", MeshladarWarning, stacklevel=user_stacklevel())
    return w


def bins_across(sinogram) -> int:
    """The most bins any view's returns span, first to last non-zero bin (0: no returns)."""
    v = np.abs(sinogram.values) > 0
    rows = v.any(axis=1)
    if not rows.any():
        return 0
    first = np.argmax(v[rows], axis=1)
    last = v.shape[1] - 1 - np.argmax(v[rows][:, ::-1], axis=1)
    return int(np.max(last - first + 1))


#: Half-widths of a reconstruction's square (cube) taken, scene units: its pixels' size
#: and their inverse stay finite at any size meshladar allocates.
EXTENT_RANGE = (1e-150, 1e300)


def default_extent(sino, extent):
    """``extent``, or when None the bins' reach (:func:`bins_reach`): the one default of
    every reconstruction (FBP, the iterative solvers, the command line).

    Parameters
    ----------
    sino : Sinogram
        The data whose bin edges give the default.
    extent : float or None
        The half-width asked for, scene units; None for the default.

    Returns
    -------
    float or object
        ``extent`` itself when not None (as given, not checked: the reconstructions check
        it), else ``bins_reach(sino)``, the half-width max(|r_0|, |r_n|), scene units.

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`.
    """
    check_sinogram("sino", sino)
    return bins_reach(sino) if extent is None else extent


def _image_square(sino, extent, center):
    """(extent, centre) of :func:`fbp`'s and compensate's square, checked before any work:
    ``extent`` (None: :func:`default_extent`, the bins' reach) in :data:`EXTENT_RANGE`,
    ``center`` a finite (2,) point."""
    extent = check_real("extent", default_extent(sino, extent), low=EXTENT_RANGE[0],
                        high=EXTENT_RANGE[1])
    c = finite_array("center", center)
    if c.shape != (2,):
        raise ParameterError(f"center must be a point (x, y); got shape {c.shape}")
    return extent, c


def bins_reach(sinogram) -> float:
    """The default half-width of a reconstruction's square (cube) about the origin: the
    bins' reach max(|r_0|, |r_n|), r_0 and r_n the first and last bin edges.

    Range r = −p·w, so a point at distance d from the origin has ranges ±d in views along
    its direction: every point whose range falls in the bins in some view is within the
    reach of the origin, and every point within it stays in the bins in every view when the
    bins straddle 0 symmetrically (the default bins of ``Ladar.covering`` and
    ``Ladar.centered``). :func:`fbp`, :func:`~meshladar.reconstruct.volumes.fbp3d`,
    :func:`~meshladar.reconstruct.volumes.fbp_slices` and the command line's
    ``reconstruct`` use it when no extent is given.

    Parameters
    ----------
    sinogram : Sinogram or (n_bins + 1,) array_like
        A record with ``bin_edges`` (a :class:`~meshladar.Sinogram`), or the bin edges
        themselves (scene units). Not checked.

    Returns
    -------
    float
        The reach max(|r_0|, |r_n|) of the first and last edge, scene units (>= 0).
    """
    edges = sinogram.bin_edges if hasattr(sinogram, "bin_edges") else sinogram
    edges = np.asarray(edges, dtype=np.float64)
    return float(max(abs(edges[0]), abs(edges[-1])))


def _check_view_sampling(sinogram):
    """Warn when the distinct view angles (:func:`_distinct_angles`: a view repeated is
    one angle) are too few for the bins across the target (streaks)."""
    across = bins_across(sinogram)
    n = _distinct_angles(sinogram.angles_deg)[0].size
    if n < 2 or across == 0:
        return
    if math.pi * across / n > _UNDERSAMPLED_RATIO:
        need = int(math.ceil(math.pi * across / 2.0))
        views = (f"{n} views" if n == sinogram.n_views else f"{n} distinct views (the "
                 f"{sinogram.n_views} views repeat {n} angles, within {ANGLE_TOL_DEG:g} deg)")
        warnings.warn(f"{views} are too few for the {across} bins across the "
                      f"target's returns: FBP samples the angles fully with about {need} (pi/2 "
                      "per bin across); expect streaks around it, or use wider bins "
                      "(meshladar.reconstruct.resample_uniform) or more views", MeshladarWarning, stacklevel=user_stacklevel())


def fbp(sinogram, size=512, extent=None, *, filter="ramp", interpolation="linear",
        center=(0.0, 0.0)):
    """Filtered backprojection of a reflective sinogram over the full circle of views.

    Parameters
    ----------
    sinogram : Sinogram
        Bin integrals (values / bin_width is taken as the Radon transform along iso-range
        lines). Non-uniform bins are resampled onto uniform ones (integrals conserved).
    size : int >= 1
        Pixels along each side of the square image.
    extent : float in [1e-150, 1e300], optional
        Half-width of the image square in scene units: it spans [−extent, extent]² about
        ``center``. Default: the bins' reach max(|r_0|, |r_n|) (:func:`bins_reach`), the
        square about the origin that holds everything the bins see, in any units (a part
        in millimetres is not cropped); the command line's ``reconstruct`` uses the same.
    filter : {"ramp", "shepp-logan", "cosine", "hamming", "hann"}, keyword-only
        scikit-image's filters and scaling.
    interpolation : {"linear", "nearest"}, keyword-only
        How filtered projections are sampled at each pixel's range.
    center : (2,) float, keyword-only
        Centre of the image square.

    Returns
    -------
    Image
        ``image[i, j]`` is the reconstruction at (image.x[j], image.y[i]). An off-centre
        disk appears at its true (x, y).

    Raises
    ------
    ParameterError
        When ``sinogram`` is not a :class:`~meshladar.Sinogram` or has view vectors off the
        x-y plane; when ``size`` is not an integer >= 1 or a ``size`` × ``size`` image (24
        bytes a pixel) would pass meshladar's 4 GiB allocation limit; when ``extent`` is
        not a finite real in [1e-150, 1e300]; when ``filter`` or ``interpolation`` is not
        one of :data:`FILTERS` or :data:`INTERPOLATIONS`; when ``center`` is not a finite
        (2,) point; or when the image would overflow float64.

    Warns
    -----
    MeshladarWarning
        When all views are at one angle, there is one range bin, there is one view, the
        views leave a gap wider than 3× their median spacing, or the views are too few for
        the bins across the target (π · bins across / n_views above 8: streaks). Both
        coverage checks count distinct angles: views within 1e-6° (mod 360°) are one.
        Without ``extent``: when the target fills less than a tenth of the image's width
        (:func:`.framing.check_frame`, naming the ``center`` and ``extent`` that fit).

    Notes
    -----
    Normalised so that the FBP of the exact Radon transform of f over 360° returns f:
    image = Σ_v w_v q_v(r), w_v half of view v's share of 2π (an angle's share split evenly
    among the views repeating it), q_v the ramp-filtered projection values_v / bin_width².
    With linear interpolation, views 180° apart on bins symmetric about 0 (to a whole
    number of bins) are backprojected as one, their profiles added with one reversed:
    half the work, the same image to the rounding of the sample positions (the
    conditions: ``meshladar.reconstruct._folded.backproject_views``).

    Examples
    --------
    >>> import meshladar as ml
    >>> from meshladar import phantoms
    >>> disk = phantoms.load("disk")
    >>> image = ml.fbp(ml.simulate(disk.scene, disk.ladar), size=256)
    >>> image.extent        # the bins' reach: the paper's 512 bins of A/256 about 0, A = 0.8
    0.8
    >>> image.values.shape, float(image.x[0]), float(image.x[-1])   # pixel centres in ±0.8
    ((256, 256), -0.796875, 0.796875)
    """
    given, (size, extent, c) = extent, _check_fbp(sinogram, size, extent, filter,
                                                  interpolation, center)
    if given is None:                      # the default square: does it hold the target?
        check_frame(sinogram, extent, c)
    sinogram, resampled = _on_uniform_bins(sinogram)
    out = _backprojected(sinogram, int(size), extent, c, filter, interpolation)
    return Image(out, extent, (float(c[0]), float(c[1])),
                 _fbp_info(sinogram, filter, interpolation, resampled))


def _on_uniform_bins(sinogram):
    """(sinogram, resampled): the sinogram as it is when its bins are uniform (their widths
    within UNIFORM_RTOL of their mean), else resampled onto uniform ones
    (:func:`resample_uniform`, integrals conserved)."""
    widths = sinogram.bin_widths
    resampled = bool(np.ptp(widths) > _UNIFORM_RTOL * widths.mean())
    if resampled:
        sinogram = resample_uniform(sinogram)
    return sinogram, resampled


def _backprojected(sinogram, size, extent, c, filter, interpolation):
    """The (size, size) image of :func:`fbp` on the square of half-width ``extent`` about
    ``c``, from a sinogram on uniform bins: each view weighted by half its share of the
    circle, filtered, backprojected, and scaled by 1 / bin width². Warns (for fbp's caller)
    when the views leave a gap or are too few; raises when the image overflows float64."""
    dr = float(np.mean(sinogram.bin_widths))
    weights = _view_weights(sinogram.angles_deg)
    _check_view_sampling(sinogram)
    # bin integrals of any magnitude (1e-300 to 1e307): filtered at unit scale (a power of
    # two, exact), the scale and 1/dr² applied once at the end
    peak = float(np.max(np.abs(sinogram.values)))
    scale = 2.0 ** math.floor(math.log2(peak)) if peak > 0 else 1.0
    q = _filtered(sinogram.values / scale, filter)

    xs = c[0] + pixel_centres(size, extent)
    ys = c[1] + pixel_centres(size, extent)
    out = np.zeros((size, size))
    _folded.backproject_views(q, sinogram.angles_deg, weights,
                              float(sinogram.bin_centers[0]), 1.0 / dr, xs, ys,
                              interpolation == "nearest", out)
    with np.errstate(over="ignore"):
        out *= scale / dr
        out /= dr
    if not np.all(np.isfinite(out)):
        raise ParameterError(f"sinogram: values up to {peak:.3g} in bins {dr:.3g} wide give an "
                             "image beyond float64's range (1.8e308); rescale the values")
    return out


def _fbp_info(sinogram, filter, interpolation, resampled):
    """The ``info`` of :func:`fbp`'s image: how it was made, and the data's preprocessing,
    radiometry and units."""
    info = {"filter": filter, "interpolation": interpolation, "n_views": sinogram.n_views,
            "n_bins": sinogram.n_bins, "resampled": resampled}
    info.update({k: v for k, v in sinogram.info.items() if k in ("preprocess", "radiometry")})
    if sinogram.units:
        info["input_units"] = sinogram.units
    return info


def _check_fbp(sinogram, size, extent, filter, interpolation, center):
    """Refuse what :func:`fbp` cannot reconstruct; returns (size, extent, centre array)."""
    if not isinstance(sinogram, Sinogram):
        raise ParameterError(f"sinogram must be a meshladar.Sinogram; got "
                             f"{type(sinogram).__name__}")
    if not sinogram.planar:
        raise ParameterError("fbp reconstructs views about the z axis; this sinogram has "
                             f"{int(np.count_nonzero(sinogram.view_vectors[:, 2]))} view "
                             "vectors off the x-y plane (3-D views), which a planar FBP "
                             "would silently misplace")
    _warn_degenerate(sinogram)
    size = check_count("size", size)
    check_size("size", size * size, 8 * 3, f"a {size} x {size} image", "use a smaller size")
    extent, c = _image_square(sinogram, extent, center)
    check_choice("filter", filter, FILTERS)
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    return size, extent, c


def _warn_degenerate(sinogram):
    """Warn (issue 29: silently a streak or zeros) when the data cannot make an image: all
    views at one angle, or a single range bin."""
    if _distinct_angles(sinogram.angles_deg)[0].size < 2 and sinogram.n_views > 1:
        warnings.warn(f"all {sinogram.n_views} views are at "
                      f"{float(np.mod(sinogram.angles_deg[0], 360.0)):g} degrees: FBP smears "
                      "one profile into a streak; it needs views all around the scene",
                      MeshladarWarning, stacklevel=user_stacklevel())
    if sinogram.n_bins < 2:
        warnings.warn("one range bin: the image has no range resolution (a uniform disk at "
                      "best); FBP needs the bins across the target", MeshladarWarning,
                      stacklevel=user_stacklevel())


def quiet_fbp(sino, size, extent, *, center=(0.0, 0.0)):
    """FBP's image values, its warnings silenced: for a starting point or a scale of another
    method (iterative, compensation), where the warnings about FBP's own output (too few
    views, gaps, one view or one bin) do not apply.

    Every :class:`~meshladar.errors.MeshladarWarning` that :func:`fbp` raises is ignored;
    its errors are not.

    Parameters
    ----------
    sino : Sinogram
        The data, as :func:`fbp`'s ``sinogram``.
    size : int >= 1
        Pixels along each side of the square image.
    extent : float in [1e-150, 1e300] or None
        Half-width of the image square, scene units; None: the bins' reach
        (:func:`bins_reach`).
    center : (2,) float, keyword-only, default (0, 0)
        Centre of the image square.

    Returns
    -------
    (size, size) ndarray of float64
        :func:`fbp`'s image values (read-only, as an :class:`~meshladar.Image`'s):
        ``[i, j]`` at (x_j, y_i).

    Raises
    ------
    ParameterError
        As :func:`fbp`.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshladarWarning)
        return fbp(sino, size=size, extent=extent, center=center).values

