"""Per-hit weights (the weigh stage's arithmetic of one hit): F(θ)·δA⊥ under the paper's
Eq. 8 or F·cos θr·δA⊥ under received power, monostatic or bistatic, per material group
(:func:`weights`), times the hits' own factors (:func:`scaled`), and the weight per unit of
a coating's projected-weight table that the compiled coating kernels interpolate
(:func:`per_table_weight`). The weights are binned by range in :mod:`.binning`."""

from __future__ import annotations

import warnings

import numpy as np

from ..brdf import projected_weight
from ..errors import MeshladarWarning, user_stacklevel
from ..precision import COS_HORIZON

__all__ = ["weights", "scaled", "per_table_weight", "warn_edge_on_receiver",
           "GRAZING_RECEIVER_COS"]


#: Below this cos θr a lit surface is edge-on to the receiver: under Eq. 8 a bistatic
#: weight is F, whose specular term grows as 1/cos θr (1e6 times its value at 60° here).
GRAZING_RECEIVER_COS = 1e-6


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


def _warn_grazing_receiver(cos_t, cos_r):
    """Warn when surfaces facing the ladar are edge-on to the receiver under
    radiometry="paper" (:func:`warn_edge_on_receiver`): per hit, or per face where the
    fused loop weighs faces in numpy."""
    if np.any((cos_t > 0) & (cos_r >= 0) & (cos_r < GRAZING_RECEIVER_COS)):
        warn_edge_on_receiver()


def warn_edge_on_receiver():
    """The warning that surfaces facing the ladar lie edge-on to the receiver under
    radiometry="paper" (the mesh engine's fused loop checks faces, the per-hit path hits):
    there F (not F·cos θr) is weighed, and its 1/cos θr makes a flat facet parallel to the
    receiver's direction dominate the profile without bound (received power is finite)."""
    warnings.warn("surfaces facing the ladar lie edge-on to the receiver (cos θr < "
                  "1e-6): under radiometry='paper' a bistatic return weighs F, which "
                  "grows as 1/cos θr there, so they dominate the profile; "
                  "radiometry='power' (received power, F·cos θr) is finite",
                  MeshladarWarning, stacklevel=user_stacklevel())


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
        ``meshladar.precision.COS_HORIZON`` (cos(fl(π/2)) = 6.1e-17, the floor
        :meth:`BRDF.value <meshladar.brdf.BRDF.value>` divides by), so the product with the
        table is :func:`weigh`'s weight up to and including grazing incidence.
    """
    omega = scaled(np.full(hits.view.size, float(hits.area)), hits.weight_factor,
                   hits.receive_factor, power=power)
    return omega if power else omega / np.maximum(hits.cos_theta, COS_HORIZON)
