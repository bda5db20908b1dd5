"""Which orders of bounces a mesh run sums: the ``bounces`` and ``bounce_samples`` options
checked before any ray, orders 2.. added to the single bounce (:mod:`.bounces`), and the
single bounce's check of a scene that needs more (:class:`~meshladar.errors.BounceWarning`).
A scene whose :meth:`~meshladar.scene.Scene.visibility` needs no bounce is never sampled:
its orders beyond the first are exact zeros."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from ..errors import BounceWarning, ModelError, ParameterError, user_stacklevel
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import embree_scene, geometry
from ..scene import Scene
from .bounces import (BOUNCE_SAMPLES, BRANCHES, _view_orders, check_bistatic,
                      higher_orders, single_bounce)

__all__ = ["MAX_BOUNCES", "MAX_BOUNCE_SAMPLES", "BOUNCE_SHARE", "check_bounces",
           "add_bounces"]


#: The most paths per view and order (given, or asked for by ``tol``): ~0.8 GB while a
#: view is sampled.
MAX_BOUNCE_SAMPLES = 1 << 22
#: The highest order ``bounces`` takes.
MAX_BOUNCES = 8
#: ``bounces="auto"`` and the single bounce's check: an order whose total is below this
#: share of the single bounce's (unless ``tol`` is given) is left out or not warned about.
BOUNCE_SHARE = 1e-2
#: The single bounce's check of a scene that needs bounces: paths per view on at most this
#: many views, first hits on a grid of about CHECK_GRID rays across the scene, orders 2 to
#: CHECK_ORDERS (a corner reflector returns at the third: its second can be nothing).
CHECK_SAMPLES, CHECK_VIEWS, CHECK_GRID, CHECK_ORDERS = 4096, 8, 64, 4
#: An order counts in the check where it passes its threshold by this many of its own
#: standard errors (a glinting coating's rare bright path made a nut's third order read
#: 7.5 % of a view's single bounce; 0.1-0.2 % with 64 times the paths).
CHECK_SIGMAS = 2.0
#: The orders' names in the check's warning.
_ORDINALS = {2: "second", 3: "third", 4: "fourth"}


def check_bounces(scene, bounces, samples, options):
    """Refuse, before any ray, what the bounce orders cannot do (module docstring).

    Parameters
    ----------
    scene : Scene
        The scene simulated.
    bounces : int or "auto" or None
        1..MAX_BOUNCES, ``"auto"``, or None (1).
    samples : int or None
        Paths per view and order, BRANCHES to MAX_BOUNCE_SAMPLES; None: BOUNCE_SAMPLES.
    options : dict
        The mesh model's other options (``sensor``, ``receiver`` and ``mode`` are read).

    Returns
    -------
    bounces : int or "auto"
        As given (1 for None).
    samples : int
        As given, or BOUNCE_SAMPLES.

    Raises
    ------
    ParameterError
        Naming the value and what is valid; ModelError for a coating without a bistatic
        evaluation (:func:`check_bistatic`).
    """
    bounces = 1 if bounces is None else bounces
    auto = isinstance(bounces, str) and bounces == "auto"
    if not auto and (isinstance(bounces, bool) or not isinstance(
            bounces, (int, np.integer)) or not 1 <= bounces <= MAX_BOUNCES):
        raise ParameterError(f"bounces must be an integer from 1 to {MAX_BOUNCES} or "
                             f"'auto'; got {bounces!r}")
    samples = BOUNCE_SAMPLES if samples is None else samples
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or \
            not BRANCHES <= samples <= MAX_BOUNCE_SAMPLES:
        raise ParameterError(f"bounce_samples must be an integer from {BRANCHES} to "
                             f"{MAX_BOUNCE_SAMPLES} (a path holds ~200 bytes while a view "
                             f"is sampled); got {samples!r}")
    if bounces != 1 and isinstance(scene, Scene) and scene.visibility().needs_bounces:
        if options.get("mode") == "slice" or (options.get("mode") is None and scene.shapes):
            raise ParameterError("bounces > 1 needs mode='3d' (a slice's light leaves "
                                 "its plane)")
        check_bistatic(scene.materials)
    return bounces, int(samples)


def add_bounces(scene, ladar, sino, bounces, samples, *, tol=None, seed=None, sensor=None):
    """The single bounce's sinogram with orders 2.. added (``bounces`` > 1 or ``"auto"``),
    or, for ``bounces=1`` on a scene that needs bounces, checked by a cheap pass that
    warns when the second order's share exceeds the threshold.

    Parameters
    ----------
    scene : Scene
        The scene (a mesh scene, or analytic shapes tessellated as the run did).
    ladar : Ladar
        The run's views and bins.
    sino : Sinogram
        The single bounce (its ``info["ray_spacing"]`` and ``radiometry`` are used).
    bounces : int or "auto"
        As checked by :func:`check_bounces`.
    samples : int
        Paths per view and order.
    tol : float, optional
        The share below which an order is left out (``"auto"``) or not warned about
        (default :data:`BOUNCE_SHARE`); given, also the accuracy: the paths per view grow
        until the bounce terms' standard error is at most ``tol / 2`` of the sinogram
        (relative L2; :func:`_sampled`).
    seed : int, optional
        Seeds the sampling.
    sensor : Sensor, optional
        The run's sensor: the orders are sampled from it (its beam, its standoff) and
        scaled to photoelectrons as the single bounce is, when it counts them.

    Returns
    -------
    Sinogram
        ``values`` the sum of the orders; ``info["bounces"]`` the orders summed,
        ``info["order_totals"]`` and ``info["order_stderr"]`` each order's total over
        the sinogram and its standard error (order 1 exact: 0), ``info["bounce_samples"]``
        the paths per view and order used, ``info["bounce_part_totals"]`` (n_views,
        n_parts) the orders beyond the first per part of each path's last surface, and
        ``info["view_stderr"]`` (n_views,) the standard error of each view's total (when
        sampled).

    Warns
    -----
    BounceWarning
        With ``bounces=1`` and the received-power radiometry, when the cheap pass (seeded:
        the same scene warns or not every time; parallel rays) puts the second order above
        the share. The paper's radiometry (the default) is the paper's single-bounce model
        unless bounces are asked for, and is not checked.
    """
    share = BOUNCE_SHARE if tol is None else tol
    if not scene.is_mesh:
        scene = scene.tessellate(1024)
    needs = scene.visibility().needs_bounces
    first = float(sino.values.sum())
    if bounces == 1 or not needs:
        if bounces == 1 and needs and sino.radiometry == "power" and \
                sino.info.get("mode") != "slice":
            _check_orders(scene, ladar, sino, share, 0 if seed is None else seed)
        n = 1 if bounces == "auto" else bounces                  # exact zeros beyond 1
        return _with_orders(sino, sino.values, n, [first] + [0.0] * (n - 1), [0.0] * n)
    top = MAX_BOUNCES if bounces == "auto" else bounces
    orders = _sampled(scene, ladar, sino, (top, samples), tol, seed, sensor)
    totals = orders.values.sum(axis=(1, 2))
    errors = np.sqrt((orders.total_stderr[0] ** 2).sum(axis=1))     # views: independent
    keep = top - 1
    if bounces == "auto":            # up to the highest order at or above the share (a
        above = np.flatnonzero(np.abs(totals) >= share * abs(first))   # corner's 2nd is 0)
        keep = int(above[-1]) + 1 if above.size else 0
    if isinstance(bounces, (int, np.integer)) and bounces < CHECK_ORDERS and \
            sino.radiometry == "power":
        _check_orders(scene, ladar, sino, share, 0 if seed is None else seed, bounces)
    values = sino.values + orders.values[:keep].sum(axis=0)
    out = _with_orders(sino, values, keep + 1, [first, *totals[:keep]],
                       [0.0, *errors[:keep]])
    shares = orders.per_part[:keep].sum(axis=0)
    views = orders.total_stderr[1, keep - 1] if keep else np.zeros(ladar.n_views)
    return replace(out, info=dict(out.info, bounce_samples=orders.samples,
                                  bounce_part_totals=shares.tolist(),
                                  view_stderr=views.tolist()))


def _sampled(scene, ladar, sino, plan, tol, seed, sensor):
    """The orders 2..top at ``samples`` paths a view (``plan``: (top, samples)), in the
    sinogram's units; with ``tol``, that run is a pilot: when the bounce terms' standard
    error (relative L2 over the sinogram) exceeds half of ``tol``, the paths grow by the
    square of the ratio (with 20 % to spare, at most MAX_BOUNCE_SAMPLES) and the orders are
    sampled again."""
    top, samples = plan

    def run(n):
        o = higher_orders(scene, ladar, bounces=top, ray_spacing=sino.info["ray_spacing"],
                          samples=n, seed=seed, receivers=_receivers(sino, ladar),
                          sensor=sensor, radiometry=sino.radiometry)
        if sensor is None or not sensor.counts_photons:
            return o
        k = sensor.photoelectrons_per_unit()
        return replace(o, values=o.values * k, stderr=o.stderr * k, per_part=o.per_part * k,
                       total_stderr=o.total_stderr * k)
    orders = run(samples)
    if tol is None:
        return orders
    norm = float(np.linalg.norm(sino.values + orders.values.sum(axis=0)))
    error = float(np.sqrt((orders.stderr ** 2).sum())) / norm if norm > 0 else 0.0
    if error <= 0.5 * tol or samples >= MAX_BOUNCE_SAMPLES:
        return orders
    return run(int(min(MAX_BOUNCE_SAMPLES, np.ceil(1.2 * samples * (error / (0.5 * tol)) ** 2))))


def _receivers(sino, ladar):
    """The run's bistatic receivers, one per view, or None (monostatic)."""
    r = sino.info.get("receiver")
    return None if r is None else np.broadcast_to(np.asarray(r, np.float64),
                                                  (ladar.n_views, 3))


def _with_orders(sino, values, n, totals, errors):
    """``sino`` with ``values`` and the orders' provenance."""
    return replace(sino, values=values, info=dict(
        sino.info, bounces=n, order_totals=[float(t) for t in totals],
        order_stderr=[float(e) for e in errors]))


def _check_orders(scene, ladar, sino, share, seed, done=1):
    """The cheap pass of a run that sums ``done`` orders (below CHECK_ORDERS) of a scene
    that needs bounces: on at most CHECK_VIEWS of the views, first hits on a grid of about
    CHECK_GRID rays across the scene, the single bounce and CHECK_SAMPLES paths of orders
    2 to CHECK_ORDERS summed over all ranges (in received power; parallel rays), view by
    view. Warns, with the worst view's shares, when in any view checked an order beyond
    ``done`` exceeds ``share`` of the single bounce (``done`` 1), or returns more than
    each order summed (``done`` 2 or more: a corner reflector's third order, its second
    nearly nothing), by CHECK_SIGMAS of its standard errors. Not done where a coating has
    no bistatic evaluation."""
    try:
        check_bistatic(scene.materials)
    except ModelError:
        return
    pick = np.unique(np.linspace(0, ladar.n_views - 1, CHECK_VIEWS).round().astype(int))
    lo, hi = scene.bounds()
    spacing = max(float(sino.info["ray_spacing"]),
                  float(np.linalg.norm(hi - lo)) / CHECK_GRID)
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, resolve_backend("embreex"))      # as higher_orders: incoherent
    ratios, sure = [], []
    for i, rng in zip(pick, np.random.SeedSequence(seed).spawn(len(pick))):
        w = np.asarray(ladar.view_vectors[i], np.float64)
        first = float(single_bounce(scene, geo, w, spacing)[1].sum())
        (sums, _), _, var = _view_orders(scene, geo, emb, w, np.array([-np.inf, np.inf]),
                                         spacing, (CHECK_ORDERS, CHECK_SAMPLES),
                                         np.random.default_rng(rng))
        if first > 0:                                             # orders 2, 3, ...
            ratios.append(sums[:, 0] / first)
            sure.append((sums[:, 0] - CHECK_SIGMAS * np.sqrt(var[0])) / first)
    if not ratios:
        return
    summed, ratios = np.split(np.array(ratios), [done - 1], axis=1)
    sure = np.array(sure)[:, done - 1:]
    # a single bounce: an order above the share; more: one above every order summed; each
    # by CHECK_SIGMAS standard errors (a rare glint path is no order's return)
    big = share if done == 1 else np.maximum(1.0, summed.max(axis=1, initial=0.0))[:, None]
    if not np.any(sure > big):
        return
    worst = ratios[np.argmax(ratios.sum(axis=1))]
    top = int(np.flatnonzero((sure > big).any(axis=0))[-1]) + done + 1
    each = ", ".join(f"the {_ORDINALS[k + done + 1]} {_share(r)}"
                     for k, r in enumerate(worst) if r > 0.1 * share)
    warnings.warn(f"this scene is not convex and its bounces beyond the first"
                  f"{'' if done == 1 else f' {done}'} return about {_share(worst.sum(), 'of')} "
                  f"the single bounce's received power in the worst of {len(ratios)} "
                  f"view{'s' if len(ratios) > 1 else ''} checked ({each}; a cheap "
                  f"estimate); bounces={top} or bounces='auto' includes them",
                  BounceWarning, stacklevel=user_stacklevel())


def _share(ratio, of=""):
    """A share of the single bounce as read: ``4.9 %`` (``of``: ``4.9 % of``), or
    ``6e+07 times`` from 10 up."""
    if ratio >= 10:
        return f"{ratio:.2g} times"
    return f"{100 * ratio:{'.0f' if ratio >= 1 else '.2g'}} %{of and ' ' + of}"
