"""numba's options for the weigh stage's compiled loops, in one place: cached on disk,
GIL-free, and compiled without numba's reference-counted runtime (NRT).

The loops allocate nothing (the caller passes their buffers: :mod:`._scratch`), so NRT
would only count references to the arrays they are handed and the views they slice: code
to compile and to run for nothing. Without it, a loop that allocated would fail to compile
instead of allocating, and a loop may not return an array (none does). Measured on a
one-view ``simulate`` of an 82k-triangle STL, its first run after an install (no cache):
the flat loop's tree compiles in 2.19–2.22 s against 2.34–2.52 s with NRT.
"""

from __future__ import annotations

from numba import njit

__all__ = ["njit_loop"]


def njit_loop(**options):
    """numba's ``njit`` for a weigh loop (module docstring), with any further ``options``
    (``inline="always"``).

    Parameters
    ----------
    **options
        More of numba's ``njit`` options.

    Returns
    -------
    callable
        The decorator.
    """
    return njit(cache=True, nogil=True, _nrt=False, **options)
