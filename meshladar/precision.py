"""Every precision constant and tolerance of the engine, in one place, each with its reason.

Modules import these under their own (private) names; change one here and every use
follows. Values are dimensionless unless a unit is named.
"""

from __future__ import annotations

import math

__all__ = [
    "COS_HORIZON", "E_MIN", "ENERGY_SLACK", "ANGLE_TOL_DEG", "DEGENERATE_AREA", "WELD_REL",
    "UNIFORM_RTOL", "OVERLAP_RTOL", "RECEIVER_LIFT", "MIN_COS_FACET", "REFINE_MIN_COS",
    "ORIGIN_MARGIN", "SCENE_RADIUS_RANGE", "FAR_RATIO", "TINY", "COUNT_SLACK", "PARALLEL_SLACK",
    "BOX_RATIO", "CAP_REL", "SIDDON_NUDGE", "SPAN_FLOOR",
]

# -- arithmetic guards ------------------------------------------------------------------------
#: A positive floor for a denominator that may be exactly 0 (a ray edge-on to its facet, an
#: empty cell, an all-zero sinogram): far below any physical quantity and above float64's
#: smallest normal (2.2e-308), so a 0 numerator still gives 0 and nothing else changes.
TINY = 1e-300
#: Slack when counting whole steps in a float ratio, ceil(span / width − slack): the rounding
#: of an exact ratio (2.0000000000000004 bins) must not add a step.
COUNT_SLACK = 1e-9
#: Two unit vectors within this of parallel (1 − |a·b|, or |a × b|) are treated as parallel:
#: a view along ±z has no horizontal frame axis; a receiver opposite the view gets no light.
PARALLEL_SLACK = 1e-12
#: A footprint trapezoid whose shorter half-width is below this fraction of the longer is a
#: box (its CDF's 1/(4ab) would lose every digit).
BOX_RATIO = 1e-12
#: A point lies on an extruded shape's flat cap when its height is within this fraction of
#: the shape's size of the cap.
CAP_REL = 1e-9
#: Siddon's entry point is nudged this fraction of a pixel into the grid, so the first pixel
#: is the one the ray enters, not its neighbour across the boundary.
SIDDON_NUDGE = 1e-12
#: The width of a single bin covering a zero range span, relative to (1 + |centre|).
SPAN_FLOOR = 1e-12

# -- BRDFs ----------------------------------------------------------------------------------

#: cos(fl(π/2)) = 6.1e-17: the cosine used in place of an exact 0 at the horizon when
#: dividing by cos θr (SR's A5, any model's F = F·cos θ / cos θ), so F stays finite where a
#: direction lies exactly in the surface. The compiled kernel uses the same value.
COS_HORIZON = math.cos(math.pi / 2)

#: Smallest accepted SR glint parameter e. The glint lobe peaks at h(0) = 1/e⁴ and the
#: bistatic F_s at grazing reflection grows like 1/(e³ cos θr): below 1e-12 these approach
#: float64 overflow (1e48 · 1.6e16 · ...), and no physical coating is that mirror-like.
E_MIN = 1e-12

#: Relative slack on an energy bound (SR's ρd + ε ≤ G(b), Phong's kd + ks ≤ 1) for the
#: rounding of a user's inputs.
ENERGY_SLACK = 1e-12

# -- scenes and meshes ----------------------------------------------------------------------

#: angles_deg given with view_vectors must match their azimuths to this (degrees).
ANGLE_TOL_DEG = 1e-6

#: Faces with area below this fraction of (bounding-box diagonal)² are degenerate: relative,
#: so a nanometre part and a 1e12-unit part lose the same faces (none of a sound mesh).
DEGENERATE_AREA = 1e-14

#: Vertices of a loaded mesh are one point when their positions agree to this fraction of
#: the mesh's size: far below any modelled feature, far above the float64 round-off of a
#: position a file recomputes (a seam written as sin 2π ≈ 2e-16 rather than 0).
WELD_REL = 2.0 ** -40

#: Relative tolerance of the analytic shapes' overlap test: boundaries that interpenetrate
#: by less than this fraction of their size count as touching (the paper's disk pair).
OVERLAP_RTOL = 1e-9

# -- the mesh engine (Embree is float32) ----------------------------------------------------

#: Rays start this far outside the bounding sphere (relative), so no face is behind them.
ORIGIN_MARGIN = 0.01

#: Occlusion rays toward a bistatic receiver start this far (relative to the scene's
#: radius) off the hit facet, above float32 round-off of the hit point (~1e-7 R).
RECEIVER_LIFT = 1e-5

#: A facet seen within this cosine of edge-on counts as seen at it: the float32 ray-facet
#: intersection is meaningless there, and it bounds a shading ray's area factor by 1e6.
MIN_COS_FACET = 1e-6

#: Below this |n·w| the float64 plane intersection is ill-conditioned and Embree's float32
#: distance is kept.
REFINE_MIN_COS = 1e-6

#: Scene sizes (bounding radius, in scene units) the mesh engine traces: float32 ray origins
#: and Embree's unit-size copy keep full precision across this range.
SCENE_RADIUS_RANGE = (1e-30, 1e30)

#: Beyond this ratio of the distance from the origin to the size, float64 ranges resolve the
#: target to worse than ~1e-7 of its size (|c|·2⁻⁵³ against its radius): a warning.
FAR_RATIO = 1e9

#: The share of the narrowest range bin that a standoff's rounding may reach before the
#: mesh model warns: ranges R − D carry ~(D + |aim|)·2⁻⁵³ of float64 rounding.
STANDOFF_ROUNDING_SHARE = 1e-3

# -- reconstruction -------------------------------------------------------------------------

#: Relative non-uniformity of bin widths accepted as uniform (rounding of edges).
UNIFORM_RTOL = 1e-9
