"""Weigh and bin (DESIGN.md's weigh stage): hits into a sinogram, F(θ)·δA⊥ per ray, binned
by range at a point or spread over its footprint. It imports the :class:`Hits` record,
never the tracer's entry points, so a material sweep re-weighs cached hits without tracing."""

from __future__ import annotations

import warnings

import numpy as np

from .._validate import check_flag
from ..errors import MeshladarWarning, ParameterError
from ..ladar import Ladar
from ..hits import Hits
from ..sinogram import Sinogram
from ..precision import BOX_RATIO, TINY
from ..sensor import check_radiometry
from ..brdf import BRDF, check_brdf, projected_weight

__all__ = ["weigh", "scaled", "per_table_weight"]


def weights(cos_t, sin_t, mat, materials, area, bi=None, power=False):
    """F·δA⊥ per hit (``radiometry="paper"``, Eq. 8), or F·cos θr·δA⊥ (``power``: what a
    receiver collects), evaluated per material group (0 where either direction is below the
    horizon): monostatic F(θ; −θ) (under power the coating's finite F·cos θ), or bistatic
    F(w, w_r) from (cos, sin) of θr and α (under power the coating's F·cos θr).

    Parameters
    ----------
    cos_t, sin_t : (k,) numpy.ndarray
        cos θ and sin θ of each hit's normal against the view direction w (cos θ < 0
        below the horizon: weight 0; −1 marks an ignored back face).
    mat : (k,) numpy.ndarray of int
        Each hit's material index into ``materials`` (not read when there is one
        coating).
    materials : sequence of BRDF
        One coating per material index.
    area : float
        δA⊥ of one ray (scene units: a length in slice mode, an area in 3-D).
    bi : (k, 4) numpy.ndarray, optional
        Bistatic rows (cos θr, sin θr, cos α, sin α): the receiver's angle to the normal
        and the half vector's (cos θr = −1 where the receiver is occluded). Default None:
        monostatic.
    power : bool
        Received power (True) or the paper's Eq. 8 (default False).

    Returns
    -------
    (k,) float64 numpy.ndarray
        Each hit's weight: F·area (paper) or F·cos θ·area, bistatic F·cos θr·area
        (power), with F in 1/sr.

    Warns
    -----
    MeshladarWarning
        Bistatic under the paper's convention, when a hit facing the ladar lies edge-on
        to the receiver (0 ≤ cos θr < :data:`GRAZING_RECEIVER_COS`).

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the monostatic weight F(θ; −θ) per ray of cross-section
    δA⊥).
    """
    def one(m, c, s, b):
        if b is None:
            return projected_weight(m, c, s) * (c >= 0) if power else m.value(c, s)
        args = (c, s, b[:, 0], b[:, 1], b[:, 2], b[:, 3])
        return m.bistatic(*args) * (b[:, 0] >= 0) if power else m.bistatic_value(*args)

    if bi is not None and not power:
        _warn_grazing_receiver(cos_t, bi[:, 0])
    if len(materials) == 1:
        return one(materials[0], cos_t, sin_t, bi) * area
    wt = np.zeros(cos_t.size)
    for k in np.unique(mat):
        sel = mat == k
        wt[sel] = one(materials[k], cos_t[sel], sin_t[sel], None if bi is None else bi[sel]) \
            * area
    return wt



#: Below this cos θr a lit surface is edge-on to the receiver: under Eq. 8 a bistatic
#: weight is F, whose specular term grows as 1/cos θr (1e6 times its value at 60° here).
GRAZING_RECEIVER_COS = 1e-6


def scaled(wt, factor=None, receive=None, *, power=False):
    """Per-hit weights ``wt`` times the hits' own factors, as every weighing applies them:
    the sensor's ``factor`` (beam irradiance, spreading, atmosphere; None: 1) and, under
    received power only, the receiver's ``receive`` factor (None: 1).

    Parameters
    ----------
    wt : (k,) numpy.ndarray
        Per-hit weights (:func:`weights`).
    factor : (k,) numpy.ndarray, optional
        The hits' ``weight_factor`` (default None: 1).
    receive : (k,) numpy.ndarray, optional
        The hits' ``receive_factor``, applied under ``power`` only (default None: 1).
    power : bool
        Received power (True) or the paper's Eq. 8 (default False).

    Returns
    -------
    (k,) numpy.ndarray
        The scaled weights: a new array, or ``wt`` itself when no factor applies.
    """
    if factor is not None:
        wt = wt * factor
    if power and receive is not None:
        wt = wt * receive
    return wt


def per_table_weight(hits, power):
    """Each hit's weight per unit of its coating's projected weight F(θ; −θ) cos θ (the
    table a coating kernel interpolates), such that the product is :func:`weigh`'s weight:
    δA⊥ × the hit's factors (:func:`scaled`), over cos θ under "paper" (whose weight is F,
    not F cos θ). Monostatic hits.

    Parameters
    ----------
    hits : Hits
        The traced hits (their ``area``, ``weight_factor``, ``receive_factor`` and
        ``cos_theta``).
    power : bool
        Received power (True) or the paper's Eq. 8 (False).

    Returns
    -------
    (k,) float64 numpy.ndarray
        Per hit, δA⊥ × its factors, divided under "paper" by cos θ floored at
        ``meshladar.precision.TINY`` (1e-300).
    """
    omega = scaled(np.full(hits.view.size, float(hits.area)), hits.weight_factor,
                   hits.receive_factor, power=power)
    return omega if power else omega / np.maximum(hits.cos_theta, TINY)


def _warn_grazing_receiver(cos_t, cos_r):
    """Warn when surfaces facing the ladar are edge-on to the receiver under
    radiometry="paper" (the mesh engine's fused loop checks faces, the per-hit path hits):
    there F
    (not F·cos θr) is weighed, and its 1/cos θr makes a flat facet parallel to the
    receiver's direction dominate the profile without bound (received power is finite)."""
    if np.any((cos_t > 0) & (cos_r >= 0) & (cos_r < GRAZING_RECEIVER_COS)):
        warnings.warn("surfaces facing the ladar lie edge-on to the receiver (cos θr < "
                      "1e-6): under radiometry='paper' a bistatic return weighs F, which "
                      "grows as 1/cos θr there, so they dominate the profile; "
                      "radiometry='power' (received power, F·cos θr) is finite",
                      MeshladarWarning, stacklevel=4)


def _box_cdf(x, h):
    return np.clip((x + h) / np.where(h > 0, 2 * h, 1.0), 0.0, 1.0)



def _trap_cdf(x, a, b):
    """CDF of A + B, A ~ U(−a, a), B ~ U(−b, b): second differences of Q(y) = y₊²/2."""
    def q(y):
        return 0.5 * np.maximum(y, 0.0) ** 2

    return np.clip((q(x + a + b) - q(x + a - b) - q(x - a + b) + q(x - a - b))
                   / np.where(a * b > 0, 4 * a * b, 1.0), 0.0, 1.0)



def _curved_spread(r, wt, curve, edges):
    """Bin each ray's weight over its cell on the locally circular exact surface.

    ``curve`` rows: (θ at the hit, θ at the cell's two ends, ρ), θ signed incidence angles.
    Range along the circle is r(θ) = r_hit + ρ(cos θ_hit − cos θ), monotone in |θ|, and the
    weight is spread uniformly in θ (arc length) over the cell; a cell straddling the top
    (θ = 0) is split there."""
    nb = len(edges) - 1
    th, ta, tb, rho = curve.T
    total = np.maximum(tb - ta, TINY)
    # pieces in |θ|: [lo, hi] with their weight share
    straddle = (ta < 0) & (tb > 0)
    lo1 = np.where(straddle, 0.0, np.minimum(np.abs(ta), np.abs(tb)))
    hi1 = np.where(straddle, -ta, np.maximum(np.abs(ta), np.abs(tb)))
    lo2 = np.zeros_like(lo1)
    hi2 = np.where(straddle, tb, 0.0)
    out = np.zeros(nb)
    ct = np.cos(th)
    for lo, hi in ((lo1, hi1), (lo2, hi2)):
        ok = hi > lo
        if not ok.any():
            continue
        rr, w, c0, rh, l, h, tot = r[ok], wt[ok], ct[ok], rho[ok], lo[ok], hi[ok], total[ok]
        r_lo = rr + rh * (c0 - np.cos(l))
        r_hi = rr + rh * (c0 - np.cos(h))
        k0 = np.clip(np.searchsorted(edges, r_lo, side="right") - 1, 0, nb - 1)
        k1 = np.clip(np.searchsorted(edges, r_hi, side="right") - 1, 0, nb - 1)
        inside = (r_hi >= edges[0]) & (r_lo < edges[-1])
        cnt = np.where(inside, k1 - k0 + 1, 0)
        rows = np.repeat(np.arange(rr.size), cnt)
        kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)

        def theta_at(edge, i):
            # |θ| where r(θ) = edge, clipped to the piece
            x = np.clip(c0[i] - (edge - rr[i]) / rh[i], -1.0, 1.0)
            return np.clip(np.arccos(x), l[i], h[i])

        t1 = theta_at(edges[kk], rows)
        t2 = theta_at(edges[kk + 1], rows)
        out += np.bincount(kk, weights=w[rows] * (t2 - t1) / tot[rows], minlength=nb)
    return out



def bin_one(r, cos_t, sin_t, mat, spread, materials, edges, area, *, footprint=False,
            bi=None, factor=None, curve=None, power=False, receive=None):
    """One view's profile (n_bins,) from its k hits: ranges ``r``, ``cos_t``/``sin_t`` of
    incidence, material ids ``mat``, footprints ``spread`` (k, 4), the coatings, bin
    edges and δA⊥; binned at a point or over the footprint; ``bi`` (k, 4) the bistatic
    angles, ``factor`` a per-hit weight factor, ``curve`` (k, 4) curved footprints,
    ``power`` received power, ``receive`` the sensor's receiver factors (applied under
    received power only).

    Bins are half-open, [edges[j], edges[j + 1]); a hit binned at a point outside the
    edges is dropped. With ``footprint``, each hit's weight is spread over the range
    interval r + [−(a + b), a + b] of its footprint's half-widths a and b, clipped to its
    facet's own interval (``spread[:, 2:]``), by the distribution of the sum of two
    uniform offsets (a box where b is negligible, a trapezoid otherwise), renormalised
    over the clipped interval; weight outside the edges is lost. With ``curve`` as well,
    rows with ρ > 0 are spread uniformly in θ over their cell on the locally circular
    surface, the rest as flat footprints.

    Parameters
    ----------
    r : (k,) numpy.ndarray
        The hits' ranges (scene units, in the frame of ``edges``).
    cos_t, sin_t : (k,) numpy.ndarray
        cos θ and sin θ of the hits' incidence (:func:`weights`).
    mat : (k,) numpy.ndarray of int
        The hits' material indices into ``materials``.
    spread : (k, 4) numpy.ndarray
        The hits' footprints: range half-widths along the two transverse axes, and the
        facet's own range interval relative to the hit (≤ 0, ≥ 0); read only with
        ``footprint``.
    materials : sequence of BRDF
        One coating per material index.
    edges : (n_bins + 1,) numpy.ndarray
        Increasing range bin edges (scene units).
    area : float
        δA⊥ of one ray.
    footprint : bool
        Spread each hit over its footprint (default False: bin at its range).
    bi : (k, 4) numpy.ndarray, optional
        Bistatic angles (:func:`weights`); default None, monostatic.
    factor : (k,) numpy.ndarray, optional
        Per-hit weight factors (:func:`scaled`); default None.
    curve : (k, 4) numpy.ndarray, optional
        Rows (θ at the hit, θ at the cell's two ends, ρ): signed incidence angles in
        radians and the surface's radius of curvature (0 for none); read only with
        ``footprint``. Default None.
    power : bool
        Received power (True) or the paper's Eq. 8 (default False).
    receive : (k,) numpy.ndarray, optional
        Receiver factors (:func:`scaled`, under ``power`` only); default None.

    Returns
    -------
    (n_bins,) float64 numpy.ndarray
        The view's profile: per bin, the sum of the weights (F·δA⊥ under Eq. 8) that fall
        in it.

    Warns
    -----
    MeshladarWarning
        As :func:`weights`, for bistatic hits edge-on to the receiver.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (P[k] = Σ F(θ_hit) δA⊥ over the hits in bin k).
    """
    nb = len(edges) - 1
    wt = scaled(weights(cos_t, sin_t, mat, materials, area, bi, power), factor, receive,
                power=power)
    if footprint and curve is not None:
        curved = curve[:, 3] > 0
        out = _curved_spread(r[curved], wt[curved], curve[curved], edges)
        flat = ~curved
        return out + bin_one(r[flat], cos_t[flat], sin_t[flat], mat[flat], spread[flat],
                             materials, edges, area, footprint=True,
                             bi=None if bi is None else bi[flat], power=power)
    if not footprint:
        k = np.searchsorted(edges, r, side="right") - 1
        ok = (k >= 0) & (k < nb)
        return np.bincount(k[ok], weights=wt[ok], minlength=nb)
    a = np.maximum(spread[:, 0], spread[:, 1])
    b = np.minimum(spread[:, 0], spread[:, 1])
    # the footprint's interval, clipped to the facet's own range interval
    lo_c = np.maximum(-(a + b), spread[:, 2])
    hi_c = np.minimum(a + b, spread[:, 3])
    point = (a <= 0) | (hi_c <= lo_c)
    k0 = np.clip(np.searchsorted(edges, r + lo_c, side="right") - 1, 0, nb - 1)
    k1 = np.clip(np.searchsorted(edges, r + hi_c, side="right") - 1, 0, nb - 1)
    k0 = np.where(point, np.clip(np.searchsorted(edges, r, side="right") - 1, 0, nb - 1), k0)
    k1 = np.where(point, k0, k1)
    inside = (r + hi_c >= edges[0]) & (r + lo_c < edges[-1]) & (wt != 0)
    cnt = np.where(inside, k1 - k0 + 1, 0)
    rows = np.repeat(np.arange(r.size), cnt)
    kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    lo = np.maximum(edges[kk] - r[rows], lo_c[rows])
    hi = np.minimum(edges[kk + 1] - r[rows], hi_c[rows])
    ar, br = a[rows], b[rows]
    tiny = br <= BOX_RATIO * np.maximum(ar, TINY)

    def cdf(x):
        return np.where(tiny, _box_cdf(x, ar), _trap_cdf(x, ar, br))

    mass = cdf(hi_c[rows]) - cdf(lo_c[rows])
    frac = np.where(hi > lo, cdf(hi) - cdf(lo), 0.0) / np.where(mass > 0, mass, 1.0)
    frac = np.where(point[rows], ((edges[kk] <= r[rows]) & (r[rows] < edges[kk + 1]))
                    .astype(float), frac)
    return np.bincount(kk, weights=wt[rows] * frac, minlength=nb)





def weigh(hits: Hits, materials=None, *, footprint=False, bin_edges=None,
          radiometry="paper") -> Sinogram:
    """Turn hits into a sinogram: F(θ)·δA⊥ per ray, binned by range.

    Parameters
    ----------
    hits : Hits
        The first hits that ``meshladar.trace`` returns.
    materials : BRDF or list or tuple of BRDF, optional
        Replacement coatings, one per material index of the traced scene (default: the
        scene's; a single BRDF stands for a one-material scene). A material sweep
        re-weighs the same hits.
    footprint : bool
        Spread each ray over the range interval its footprint covers on the hit facet
        (default False). Monostatic hits of parallel rays only.
    bin_edges : array_like, optional
        Other range bins (default the ladar's), increasing, scene units.
    radiometry : {"paper", "power"}
        "paper" (default): Eq. 8, Σ F(θ_hit)·δA⊥; "power": received power, Σ F·cos θr·δA⊥
        (:mod:`meshladar.sensor`). The same hits serve both.

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins): per bin, the weights of the rays whose first hit
        lies in it, model "mesh"; ``info`` records the radiometry, mode, normals, footprint,
        ray spacing, sampling, seed, rays and back-face hits (and backend, units, and where
        they apply z0, receiver and sensor: :func:`sinogram_of`).

    Raises
    ------
    ParameterError
        When ``hits`` is not a Hits; ``footprint`` is not a bool; ``radiometry`` is not
        one of its choices; ``footprint`` meets bistatic hits or hits traced with a
        sensor; ``materials`` is not a BRDF, list or tuple, holds a non-BRDF, or does not
        give one coating per material index; ``bin_edges`` are not at least two strictly
        increasing edges; the hits' sensor needs ``radiometry="power"``
        (:func:`sinogram_of`).
    ModelError
        When a coating does not define ``projected``.

    References
    ----------
    Jin & Levine (2009), Eq. 8.
    """
    if not isinstance(hits, Hits):
        raise ParameterError(f"hits must be the Hits that meshladar.trace returns; got "
                             f"{type(hits).__name__}")
    check_flag("footprint", footprint)
    power = check_radiometry(radiometry)
    if footprint and hits.bistatic is not None:
        raise ParameterError("footprint binning is monostatic only; these hits are bistatic")
    if footprint and hits.info.get("traced_with") is not None:
        raise ParameterError("footprint binning is for parallel rays without a sensor; these "
                             "hits were traced with one")
    if isinstance(materials, BRDF):
        materials = [materials]                       # one coating for a one-material scene
    if materials is not None and not isinstance(materials, (list, tuple)):
        raise ParameterError(f"materials must be a list of coatings, one per material index; "
                             f"got {type(materials).__name__}")
    mats = hits.materials if materials is None else tuple(materials)
    for i, m in enumerate(mats):
        check_brdf(f"materials[{i}]", m)
    if len(mats) != len(hits.materials):
        raise ParameterError(f"materials must give {len(hits.materials)} coatings (one per "
                             f"material index); got {len(mats)}")
    if bin_edges is None:
        edges = hits.ladar.bin_edges
    else:
        edges = Ladar([0.0], bin_edges).bin_edges      # the ladar's own checks of edges
    order = np.argsort(hits.view, kind="stable")
    bounds = np.searchsorted(hits.view[order], np.arange(hits.ladar.n_views + 1))
    vals = np.zeros((hits.ladar.n_views, len(edges) - 1))
    for i in range(hits.ladar.n_views):
        sel = order[bounds[i]:bounds[i + 1]]
        vals[i] = bin_one(hits.range[sel], hits.cos_theta[sel], hits.sin_theta[sel],
                          hits.material[sel], hits.spread[sel], mats, edges, hits.area,
                          footprint=footprint,
                          bi=None if hits.bistatic is None else hits.bistatic[sel],
                          factor=None if hits.weight_factor is None else hits.weight_factor[sel],
                          curve=None if hits.curve is None else hits.curve[sel], power=power,
                          receive=None if hits.receive_factor is None
                          else hits.receive_factor[sel])
    return sinogram_of(vals, hits.ladar, edges, hits.info, normals=hits.normals,
                       footprint=footprint, rays=hits.rays, back=hits.back_face_hits,
                       radiometry=radiometry)



def sinogram_of(vals, ladar, edges, run, *, normals, footprint, rays, back, radiometry):
    """The mesh model's sinogram of binned ``vals`` (n_views, n_bins); its info says how it
    was made (``run``: mode, spacing, sampling, seed, receiver, sensor; normals, footprint,
    rays and back-face hits per view) and under which convention (radiometry).

    Parameters
    ----------
    vals : (n_views, n_bins) numpy.ndarray
        The binned profiles.
    ladar : meshladar.Ladar
        The views (their angles, and their view vectors when not all in the x-y plane).
    edges : (n_bins + 1,) numpy.ndarray
        The range bin edges.
    run : dict
        The run's parameters: ``"mode"``, ``"ray_spacing"``, ``"sampling"``, ``"seed"``,
        ``"z0"`` (slice mode), and optionally ``"backend"``, ``"receiver"`` and
        ``"sensor"``.
    normals : str
        The hits' normals, recorded.
    footprint : bool
        Whether footprint binning was used, recorded.
    rays : array_like of int
        Rays cast per view; their sum is recorded.
    back : array_like of int
        Back-face hits per view, recorded as a list.
    radiometry : {"paper", "power"}
        The convention of ``vals``, recorded.

    Returns
    -------
    Sinogram
        Model ``"mesh"``, with ``info`` holding the above and ``"units"``
        (``"length/sr (per unit height)"`` in slice mode, ``"area/sr"`` in 3-D, or
        ``"photoelectrons"``). With a sensor that counts photons, the values are
        multiplied by ``sensor.photoelectrons_per_unit()``.

    Raises
    ------
    ParameterError
        When the run's sensor has a non-zero extinction or counts photoelectrons and
        ``radiometry`` is not ``"power"``.
    """
    info = {"radiometry": radiometry, "mode": run["mode"], "normals": normals,
            "footprint": footprint, "ray_spacing": run["ray_spacing"],
            "sampling": run["sampling"], "seed": run["seed"], "rays": int(np.sum(rays)),
            "back_face_hits": np.asarray(back).tolist(), "backend": run.get("backend"),
            "units": "length/sr (per unit height)" if run["mode"] == "slice" else "area/sr"}
    if run["mode"] == "slice":
        info["z0"] = run["z0"]
    receiver = run.get("receiver")
    if receiver is not None:                 # bistatic: the receiver's direction(s)
        rows = np.unique(np.asarray(receiver, dtype=np.float64), axis=0)
        info["receiver"] = rows[0].tolist() if len(rows) == 1 else \
            np.asarray(receiver, dtype=np.float64).tolist()
    sensor = run.get("sensor")
    if sensor is not None:
        info["sensor"] = sensor.describe()
        if sensor.extinction > 0 and radiometry != "power":
            raise ParameterError(f"extinction ({sensor.extinction:g} per m) attenuates the "
                                 "received power: use radiometry='power' (Eq. 8 has no "
                                 "receiver; the paper convention ignores the atmosphere)")
        if sensor.counts_photons:
            if radiometry != "power":
                raise ParameterError("a sensor with pulse_energy and aperture_diameter counts "
                                     "photoelectrons of received power: use "
                                     "radiometry='power' (or drop them for Eq. 8)")
            vals = vals * sensor.photoelectrons_per_unit()
            info["units"] = "photoelectrons"
    return Sinogram(vals, angles_deg=ladar.angles_deg, bin_edges=edges, model="mesh",
                    view_vectors=None if ladar.planar else ladar.view_vectors, info=info)
