"""The weigh stage: every weight and every binning of first hits (layer 5 of the guide's
Layout page).

:mod:`.record` (the :class:`Weighing` record, whose ``check(plan)`` refuses every
inapplicable combination before the first ray), :mod:`.hit_weights` (per-hit weights
F·δA⊥), :mod:`.binning` (one view's point, footprint and curved bins), :mod:`.per_hit`
(:func:`weigh` of cached :class:`~meshladar.hits.Hits`, and the mesh model's sinogram),
:mod:`.faces` (per-face weights and footprints of a view, for the compiled loops),
:mod:`.resolved` (binning by one to three coordinates), :mod:`.sensor_view` (a perspective
view binned by the compiled loop), :mod:`.fused` (the packet backend's cast-weigh-bin
loop), ``._kernels`` and ``._fused_kernels`` (the compiled loops). It imports the
:class:`Hits` record and the ray-casting stage below it, never the forward models' entry
points."""

from __future__ import annotations

from .record import Weighing
from .binning import bin_one
from .hit_weights import GRAZING_RECEIVER_COS, per_table_weight, scaled, weights
from .per_hit import sinogram_of, weigh


__all__ = ["weigh", "Weighing", "weights", "bin_one", "sinogram_of",
           "GRAZING_RECEIVER_COS", "scaled", "per_table_weight"]
