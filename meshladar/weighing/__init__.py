"""The weigh stage (DESIGN.md layer 5): every weight and every binning of first hits.

:mod:`.record` (the :class:`Weighing` record, whose ``check(plan)`` refuses every
inapplicable combination before the first ray), :mod:`.per_hit` (per-hit weights F·δA⊥,
point/footprint/curved bins, :func:`weigh` of cached :class:`~meshladar.hits.Hits`),
:mod:`.faces` (per-face weights and footprints of a view, for the compiled loops),
:mod:`.resolved` (binning by one to three coordinates), :mod:`.sensor_view` (a perspective
view binned by the compiled loop), :mod:`.fused` (the packet backend's cast-weigh-bin
loop), ``._kernels`` and ``._fused_kernels`` (the compiled loops). It imports the
:class:`Hits` record and the ray-casting stage below it, never the forward models' entry
points."""

from __future__ import annotations

from .record import Weighing
from .per_hit import (GRAZING_RECEIVER_COS, bin_one, per_table_weight, scaled, sinogram_of,
                      weigh, weights)


__all__ = ["weigh", "Weighing", "weights", "bin_one", "sinogram_of",
           "GRAZING_RECEIVER_COS", "scaled", "per_table_weight"]
