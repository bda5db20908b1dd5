"""The mesh engine (``model="mesh"``): Embree first hits, their weights (any BRDF), range bins.

Per view, an orthographic grid of parallel rays covers the scene's projected extent (the
convex hull's projection, not a fixed square) and travels along −w from just outside the
scene. Embree (embreex) returns each ray's first hit: that is the shadowing, so a monostatic
ladar casts no other ray. Each hit carries its range, cos θ of the chosen normal, the face's
material, and its footprint; weighing turns hits into bins with F(θ)·δA⊥ per ray
(P[k] = Σ F(θ_hit) δA⊥ over the rays whose first hit lies in bin k).

Two modes:

* ``mode="slice"`` (views about z): one row of rays in the plane z = z0, spaced δs; each
  ray stands for a strip δs wide and one unit high, so values are per unit height and match
  the analytic 2-D profile of an extruded phantom.
* ``mode="3d"``: a square grid of rays spaced δ (δA⊥ = δ²), any view vectors.

Precision (Embree works in float32): the scene is shifted to its bounding-box centre in
float64 before it is converted, rays start just outside its bounding sphere, and each hit's
distance is recomputed in float64 against the hit face's float64 plane, from the float32
origin exactly as cast: r = −c·w + t − o·w. A scene far from the origin or tiny keeps its
range accuracy relative to its own size, and a surface lying on a bin edge (the paper's
first edge is the disk's top, where the glint peaks) is binned to float64 precision.

Normals: ``"flat"`` (the face's geometric normal, float64), ``"smooth"`` (vertex normals
interpolated with Embree's barycentrics, averaged only across edges sharper than
``CREASE_DEG``), ``"exact"`` (the analytic shape's own normal at the hit point, for scenes
tessellated from analytic shapes).

Grazing incidence: a glossy coating's F grows like 1/cos θ toward a silhouette (A5), an
integrable singularity of the integrand per unit projected area; point samples of it
converge slowly there (~δ^½), so bins at a silhouette are the last to converge for
non-Lambertian coatings. Bins away from silhouettes converge at the facet and ray rates.

Footprint binning (``footprint=True``): a ray of width δ hitting a flat facet covers a range
interval, not a point: along the transverse axis u the range changes at dr/du = (n·u)/(n·w).
The ray's weight is spread over that interval (a box in slice mode; in 3-D the sum of the u
and v boxes, a trapezoid), exactly as the flat facet would return it.

Layout (this stage only casts; layer 4 of the guide's Layout page): :mod:`.plan` (the
:class:`~meshladar.raytrace.plan.TracePlan` record, built and validated once by
:func:`~meshladar.raytrace.plan.plan_trace`), :mod:`.grid` (ray grids and their defaults),
:mod:`.views` (one view's parallel rays → :class:`~meshladar.hits.ViewHits`),
:mod:`.perspective` (a sensor's rays), :mod:`.embree` (the geometry a worker traces and the
per-process cache of Embree scenes), :mod:`.backends` (the backend registry), with
:mod:`.packets` (+ :mod:`.embree4`, :mod:`.embree4_ctypes`, :mod:`.embree4_kernels`: the
packet library through ctypes and numba) and :mod:`.embreex_backend` registering themselves.
Weights and bins are :mod:`meshladar.weighing`'s; the entry points :func:`trace`,
:func:`simulate_mesh`, :func:`first_hits`, :func:`occluded` and the per-chunk job
:mod:`meshladar.forward`'s.
"""

from __future__ import annotations

import importlib

from .._deprecated import warn_moved

from .embree import BACKENDS
from .grid import MODES, SAMPLINGS
from ..hits import Hits
from .views import BACK_FACES, NORMALS

__all__ = ["Hits", "trace", "simulate_mesh", "first_hits", "occluded", "NORMALS", "MODES",
           "BACK_FACES", "SAMPLINGS", "BACKENDS"]

#: The entry points moved to :mod:`meshladar.forward.mesh` (layer 7); they stay reachable
#: here by name for one release, loaded on first use (no import of a layer above).
_ENTRY_POINTS = ("trace", "simulate_mesh", "first_hits", "occluded")


def __getattr__(name):
    if name in _ENTRY_POINTS:
        warn_moved(f"raytrace.{name}", f"forward.mesh.{name}")
        return getattr(importlib.import_module("meshladar.forward.mesh"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
