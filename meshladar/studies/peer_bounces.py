"""Light beyond one bounce against Mitsuba 3 + mitransient: the total received power of
each order of bounces (meshladar's ``radiometry="power"``) from renders at increasing
``max_depth`` with one seed, whose differences are each order's estimate.

Only totals are compared: mitransient's directional emitter counts a constant length for
the light's leg to the first surface, so its path lengths of orders beyond the first are
not the plane wave's (meshladar bins each path at half its true optical path), while the
power each order carries is the same.
"""

from __future__ import annotations

import numpy as np

from .peer import _mitsuba, _uniform_width
from ._mitsuba_scene import _checked, _frame, _opl_mapping, _samples, _target, _transient_scene

__all__ = ["mitransient_orders"]


def mitransient_orders(vertices, faces, view, *, bsdf, bounces=2, spp=256, film=(128, 128),
                       seed=0, sampler="independent"):
    """Total received power of orders 1..``bounces`` rendered by mitransient (module
    docstring): one render per ``max_depth`` = order + 1, same seed and sampler, so that
    each difference is that order's own estimate.

    Parameters
    ----------
    vertices, faces : (n, 3) float, (m, 3) int
        The mesh (two-sided).
    view : (3,) array_like
        w, from the scene toward the sensor and the emitter's source (collocated).
    bsdf : dict
        A Mitsuba BSDF dictionary (``{"type": "diffuse", ...}``, ``roughconductor``, …).
    bounces : int
        The highest order.
    spp : int
        Samples per pixel.
    film : (nx, ny)
        Pixels, square, covering the mesh's bounding sphere.
    seed : int
        The sampler's seed (the same for every depth).
    sampler : str
        Mitsuba sampler plugin.

    Returns
    -------
    (bounces,) numpy.ndarray
        Each order's total, ∫ F cos θi cos θr dA and its higher-order analogues, in
        meshladar's units (per unit irradiance).
    """
    v, f, w, _ = _checked(vertices, faces, view, [0.0, 1.0])
    nx, ny = int(film[0]), int(film[1])
    spp = _samples(spp, sampler)
    mi, dr = _mitsuba()
    mesh = _target(mi, v, f, bsdf, True)
    fr = _frame(mi, v, w, nx, ny)
    reach = 2.0 * (bounces + 2) * fr.rad
    edges = np.array([-(-(fr.origin @ w)) - reach, -(fr.origin @ w) + reach])
    edges = np.array([float(-(fr.origin @ w)) - reach, float(-(fr.origin @ w)) + 2 * reach])
    mapping = _opl_mapping(mi, mesh, w, fr, edges, _uniform_width(edges))
    totals = []
    for depth in range(2, bounces + 2):
        scene = _transient_scene(mi, mesh, w, fr, {
            "sampler": {"type": sampler, "sample_count": spp, "seed": int(seed)},
            "film": {"type": "transient_hdr_film", "width": nx, "height": ny,
                     "temporal_bins": 1, "bin_width_opl": mapping["bin_width_opl"],
                     "start_opl": max(mapping["start_opl"], 0.0),
                     "rfilter": {"type": "box"}}}, max_depth=depth)
        _, transient = mi.render(scene, spp=spp, seed=int(seed))
        totals.append(float(np.array(transient, dtype=np.float64)[..., 0].sum())
                      * (2.0 * fr.h / nx) ** 2)
        dr.sync_thread()
    return np.diff(np.r_[0.0, totals])
