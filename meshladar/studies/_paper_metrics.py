"""The metrics of the paper's findings, measured on reconstructed images and volumes: edge
darkening of a disk (:func:`disk_darkening`), of an ellipse's ends and sides
(:func:`ellipse_darkening`) and of a sphere's shell (:func:`shell_darkening`), and the gray
disk's visibility beside the aluminium one (:func:`ring_visibility`).

Their definitions, and what the paper's set-up gives, are the docstring of
:mod:`meshladar.studies.paper`, which computes them and re-exports these functions.
"""

from __future__ import annotations

import math

import numpy as np

from ..shapes import from_frame

__all__ = ["disk_darkening", "ellipse_darkening", "ring_visibility", "shell_darkening"]


def disk_darkening(image, radius, power, center=(0.0, 0.0)):
    """(darkening, width) of a reconstructed disk; see the module docstring.

    The radial profile is sampled at 4001 radii from 0 to R (``Image.radial_profile``: the
    mean over each circle).

    Parameters
    ----------
    image : Image
        The reconstruction.
    radius : float
        R, the disk's radius, scene units.
    power : float
        P̄, the mean returned power per view (the mean over views of each view's sum of
        bins), in the sinogram's units; not 0.
    center : (2,) float
        The disk's centre (x, y), scene units (default the origin).

    Returns
    -------
    darkening : float
        (mean profile over 0.90 R < ρ < 0.97 R − mean over 0.60 R < ρ < 0.80 R) × πR² / P̄:
        negative when the surface band is darker than the interior.
    width : float
        The radial extent, in units of R, of the radii in 0.60 R < ρ < 0.97 R where the
        profile is below the interior mean by more than half the trough's depth (from
        the first such radius to the last); 0.0 when there is none.
    """
    radii = np.linspace(0.0, radius, 4001)
    prof = image.radial_profile(radii, center=center)
    deep = prof[(radii > 0.60 * radius) & (radii < 0.80 * radius)].mean()
    band = prof[(radii > 0.90 * radius) & (radii < 0.97 * radius)].mean()
    darkening = (band - deep) * math.pi * radius**2 / power
    # width of the trough just inside the surface: below deep − ½ (deep − min)
    inner = (radii > 0.60 * radius) & (radii < 0.97 * radius)
    drop = deep - prof[inner].min()
    below = inner & (prof < deep - 0.5 * drop)
    width = (radii[below].max() - radii[below].min()) / radius if below.any() else 0.0
    return float(darkening), float(width)


def ellipse_darkening(image, ellipse, power):
    """(ends, sides) darkening of a reconstructed ellipse; see the module docstring.

    The boundary is sampled at 1440 eccentric angles t; the band at 8 depths from 0.03 to
    0.10 × min(A, B) along the inward normal; the interior level is the mean over points
    0.3 to 0.6 of the way from the centre to the boundary (7 fractions, every angle).

    Parameters
    ----------
    image : Image
        The reconstruction.
    ellipse : Ellipse
        The true shape (its ``axes`` (A, B), ``center``, ``angle`` and ``boundary``).
    power : float
        P̄, the mean returned power per view (the mean over views of each view's sum of
        bins), in the sinogram's units; not 0.

    Returns
    -------
    ends : float
        (band mean over |cos t| > 0.95 − interior level) × πAB / P̄: the ends of the A
        semi-axis (the tapered ends when A is the major one).
    sides : float
        The same over |sin t| > 0.95: the ends of the B semi-axis.
    """
    a, b = ellipse.axes
    t = np.linspace(0.0, 2 * math.pi, 1440, endpoint=False)
    nl = np.stack([b * np.cos(t), a * np.sin(t)], -1)
    nl /= np.linalg.norm(nl, axis=-1, keepdims=True)
    n = np.stack(from_frame(ellipse.angle, nl[:, 0], nl[:, 1]), -1)
    p = ellipse.boundary(t)
    depths = np.linspace(0.03, 0.10, 8) * min(a, b)
    band = np.mean([image.sample(p - d * n) for d in depths], axis=0)
    c = np.asarray(ellipse.center)
    interior = np.mean([image.sample(c + s * (p - c)) for s in np.linspace(0.3, 0.6, 7)])
    area = math.pi * a * b
    ends = np.abs(np.cos(t)) > 0.95
    sides = np.abs(np.sin(t)) > 0.95
    return (float((band[ends].mean() - interior) * area / power),
            float((band[sides].mean() - interior) * area / power))


def ring_visibility(image, gray_disk, al_disk, bin_width):
    """The gray disk's ring mean over the aluminium disk's (annuli of ±2 bins); NaN when
    the aluminium ring is exactly 0.

    A disk's ring mean: the mean of the image's radial profile about the disk's centre at
    17 radii evenly spaced over radius ± 2 ``bin_width``.

    Parameters
    ----------
    image : Image
        The reconstruction of the disk pair.
    gray_disk, al_disk : Disk
        The dark gray and the aluminium disk (their ``center`` and ``radius``).
    bin_width : float
        The range bin width, scene units.

    Returns
    -------
    float
        The gray ring's mean over the aluminium ring's (both signed), or NaN when the
        aluminium ring's mean is exactly 0.
    """

    def ring(d):
        radii = d.radius + np.linspace(-2, 2, 17) * bin_width
        return image.radial_profile(radii, center=d.center).mean()

    gray, al = float(ring(gray_disk)), float(ring(al_disk))
    if al == 0.0:                      # no aluminium ring left: the ratio is undefined
        return math.nan
    return gray / al


def shell_darkening(volume, radius, power, center=(0.0, 0.0, 0.0)):
    """3-D edge darkening: (mean over the spherical shell 0.85-0.95 R − mean over the deeper
    interior 0.4-0.6 R) × (4/3)πR³ / P̄, with P̄ the mean returned power per view (the band
    sits further inside than the 2-D metric's because a volume's resolution is coarser).

    Parameters
    ----------
    volume : Volume
        The reconstruction; its radial profile is sampled at 201 radii from 0 to R.
    radius : float
        R, the sphere's radius, scene units.
    power : float
        P̄, in the sinogram's units; not 0.
    center : (3,) float
        The sphere's centre, scene units (default the origin).

    Returns
    -------
    float
        The darkening: negative when the shell is darker than the interior.
    """
    radii = np.linspace(0.0, radius, 201)
    prof = volume.radial_profile(radii, center=center)
    deep = prof[(radii > 0.4 * radius) & (radii < 0.6 * radius)].mean()
    band = prof[(radii > 0.85 * radius) & (radii < 0.95 * radius)].mean()
    return float((band - deep) * (4.0 / 3.0) * math.pi * radius ** 3 / power)


def _shell_peak(volume, center, radius):
    """A sphere's shell peak: the largest value of the volume's radial profile about
    ``center`` within two voxels of ``radius``."""
    d = float(np.diff(volume.x[:2])[0])
    return float(volume.radial_profile(radius + np.linspace(-2, 2, 17) * d,
                                       center=center).max())
