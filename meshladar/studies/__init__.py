"""Studies built on the engine: faceting against the exact profiles (:mod:`.faceting`),
reconstruction methods (:mod:`.reconstruction`), the paper's experiments (:mod:`.paper`),
the peer renderer Mitsuba 3 + mitransient (:mod:`.peer`) and ``meshladar bench``
(:mod:`.bench`, :mod:`.bench_mesh`, :mod:`.timing`).

The faceting study's names are re-exported here, as ``meshladar.studies`` was that module.
"""

from __future__ import annotations

from .._lazy import lazy_attributes as _lazy_attributes

from .faceting import (COATINGS, PHANTOMS, SETTINGS,
                       convergence_orders, faceting_study, report, save_study, study_scene)

__all__ = ["PHANTOMS", "COATINGS", "SETTINGS", "faceting_study", "convergence_orders",
           "study_scene", "save_study", "report"]

#: The studies' modules, loaded on first use as attributes (``meshladar.studies.bench``).
_SUBMODULES = ("bench", "bench_gpu", "bench_mesh", "faceting", "paper", "peer",
               "reconstruction", "timing")


__getattr__, __dir__ = _lazy_attributes(__name__, globals(), submodules=_SUBMODULES)
