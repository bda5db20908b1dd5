"""Independent references for the analytic model: adaptive quadrature and ray sampling.

Neither uses meshladar.forward.analytic. Geometry comes from the shapes' implicit functions (normals
are their gradients), breakpoints are found numerically (sampling + brentq / bisection), and
visibility by casting a ray from each boundary point toward the ladar against every shape.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate, optimize


def _frame(shape):
    a, b = shape.axes
    ca, sa = math.cos(shape.angle), math.sin(shape.angle)
    return a, b, ca, sa, np.asarray(shape.center, dtype=np.float64)


def _to_local(shape, p):
    a, b, ca, sa, c = _frame(shape)
    d = p - c
    return np.stack([ca * d[..., 0] + sa * d[..., 1], -sa * d[..., 0] + ca * d[..., 1]], -1)


def _dir_local(shape, v):
    a, b, ca, sa, c = _frame(shape)
    return np.stack([ca * v[..., 0] + sa * v[..., 1], -sa * v[..., 0] + ca * v[..., 1]], -1)


def ray_entry_range(shape, s, w, u):
    """Range r at which the rays p = s u − r w (one per s) enter ``shape``; inf if missed."""
    a, b, *_ = _frame(shape)
    s = np.asarray(s, dtype=np.float64)
    o = _to_local(shape, s[..., None] * u)                 # ray point at r = 0
    d = _dir_local(shape, -np.broadcast_to(w, o.shape))    # direction of increasing r
    qa = (d[..., 0] / a) ** 2 + (d[..., 1] / b) ** 2
    qb = 2 * (o[..., 0] * d[..., 0] / a**2 + o[..., 1] * d[..., 1] / b**2)
    qc = (o[..., 0] / a) ** 2 + (o[..., 1] / b) ** 2 - 1
    disc = qb * qb - 4 * qa * qc
    hit = disc > 0
    root = np.where(hit, (-qb - np.sqrt(np.where(hit, disc, 0.0))) / (2 * qa), np.inf)
    return root


def _normal(shape, p):
    a, b, ca, sa, c = _frame(shape)
    q = _to_local(shape, p)
    gl = np.stack([q[..., 0] / a**2, q[..., 1] / b**2], -1)
    g = np.stack([ca * gl[..., 0] - sa * gl[..., 1], sa * gl[..., 0] + ca * gl[..., 1]], -1)
    return g / np.linalg.norm(g, axis=-1, keepdims=True)


def ray_sample(scene, phi, edges, n_rays):
    """Brute force: n_rays parallel rays (midpoint grid across the scene), first hits
    binned with weight F(θ) δs (a ray of cross-section δs covers δs / cos θ of arc, so
    Σ F δs → ∫ F cos θ dl). Returns (profile, δs, per-bin max weight)."""
    w = np.array([math.cos(phi), math.sin(phi)])
    u = np.array([-w[1], w[0]])
    (cx, cy), radius = scene.bounding_circle()
    s0 = cx * u[0] + cy * u[1]
    ds = 2 * radius / n_rays
    s = s0 - radius + (np.arange(n_rays) + 0.5) * ds
    ranges = np.stack([ray_entry_range(sh, s, w, u) for sh in scene.shapes])
    which = np.argmin(ranges, axis=0)
    r = ranges[which, np.arange(n_rays)]
    hit = np.isfinite(r)
    s, r, which = s[hit], r[hit], which[hit]
    p = s[:, None] * u - r[:, None] * w
    prof = np.zeros(len(edges) - 1)
    wmax = np.zeros(len(edges) - 1)
    k = np.searchsorted(edges, r, side="right") - 1
    ok = (k >= 0) & (k < len(edges) - 1)
    for i, sh in enumerate(scene.shapes):
        sel = ok & (which == i)
        n = _normal(sh, p[sel])
        cos_t = np.clip(n @ w, 0.0, 1.0)
        theta = np.arctan2(np.abs(n[:, 0] * w[1] - n[:, 1] * w[0]), cos_t)
        wt = sh.material.monostatic(theta)
        np.add.at(prof, k[sel], wt * ds)
        np.maximum.at(wmax, k[sel], wt)
    return prof, ds, wmax


def quad_profile(scene, phi, edges, *, n_scan=4000, epsrel=1e-12, power=False):
    """Adaptive quadrature of P[k] = ∫ F cos θ dl (``power``: ∫ F cos²θ dl, received power)
    over visible boundary points in bin k."""
    w = np.array([math.cos(phi), math.sin(phi)])
    u = np.array([-w[1], w[0]])
    prof = np.zeros(len(edges) - 1)
    for i, sh in enumerate(scene.shapes):
        a, b, ca, sa, c = _frame(sh)
        others = [o for j, o in enumerate(scene.shapes) if j != i]

        def point(t):
            x, y = a * np.cos(t), b * np.sin(t)
            return np.stack([c[0] + ca * x - sa * y, c[1] + sa * x + ca * y], -1)

        def speed(t):
            return np.hypot(a * np.sin(t), b * np.cos(t))

        def rng(t):
            return -(point(t) @ w)

        def facing(t):
            return _normal(sh, point(t)) @ w

        def visible(t):
            p = point(t)
            if facing(t) <= 0:
                return False
            s = p @ u
            r = -(p @ w)
            return all(ray_entry_range(o, np.array([s]), w, u)[0] > r for o in others)

        def weight(t):
            n = _normal(sh, point(t))
            cos_t = max(float(n @ w), 0.0)
            theta = math.atan2(abs(n[0] * w[1] - n[1] * w[0]), cos_t)
            extra = cos_t if power else 1.0
            return sh.material.monostatic(theta, projected=True) * extra * speed(t)

        t = np.linspace(0, 2 * math.pi, n_scan + 1)
        bps = set()
        fv = np.array([facing(x) for x in t])
        vis = np.array([visible(x) for x in t])
        rv = rng(t)
        for j in range(n_scan):
            lo_t, hi_t = t[j], t[j + 1]
            if (fv[j] > 0) != (fv[j + 1] > 0):
                bps.add(optimize.brentq(facing, lo_t, hi_t, xtol=1e-15))
            if vis[j] != vis[j + 1]:
                x0, x1 = lo_t, hi_t
                for _ in range(60):
                    xm = 0.5 * (x0 + x1)
                    if visible(xm) == vis[j]:
                        x0 = xm
                    else:
                        x1 = xm
                bps.add(0.5 * (x0 + x1))
            for e in edges:
                if (rv[j] - e) * (rv[j + 1] - e) < 0:
                    bps.add(optimize.brentq(lambda x: rng(x) - e, lo_t, hi_t, xtol=1e-15))
        # the glint centre: the range minimum (normal along w)
        # (the zero of the signed n × w next to the sampled minimum of range)
        jmin = int(np.argmin(rv[:-1]))
        dt = t[1] - t[0]

        def cross(x):
            n = _normal(sh, point(x))
            return n[0] * w[1] - n[1] * w[0]

        t_top = optimize.brentq(cross, t[jmin] - dt, t[jmin] + dt, xtol=1e-15) % (2 * math.pi)
        bps.add(t_top)
        pts = np.array(sorted(bps | {0.0, 2 * math.pi}))
        for x0, x1 in zip(pts[:-1], pts[1:]):
            if x1 <= x0:
                continue
            xm = 0.5 * (x0 + x1)
            if not visible(xm):
                continue
            k = np.searchsorted(edges, rng(xm), side="right") - 1
            if not 0 <= k < len(edges) - 1:
                continue
            inner = [x for x in (t_top,) if x0 < x < x1]
            val, _ = integrate.quad(weight, x0, x1, points=inner or None, epsabs=0.0,
                                    epsrel=epsrel, limit=400)
            prof[k] += val
    return prof
