"""numba's options for the weigh stage's compiled loops, in one place: cached on disk,
GIL-free, and compiled without numba's reference-counted runtime (NRT).

The loops allocate nothing (the caller passes their buffers: :mod:`._scratch`), so NRT
would only count references to the arrays they are handed and the views they slice: code
to compile and to run for nothing. Without it, a loop that allocated would fail to compile
instead of allocating, and a loop may not return an array (none does). numba passes the
option down to the compiled helpers a loop calls that do not set their own (the scalar
``brdf._sandford_robertson_kernel.sr_bistatic``), so an allocation in one of those fails
to compile too. Measured on a one-view ``simulate`` of an 82k-triangle STL, its first run
after an install (no cache): the flat loop's tree compiles in 2.10–2.28 s against
2.41–2.45 s with NRT (four paired runs).

numba's cache does not key on these options: it is invalidated by a change to the file
that defines a loop. After editing :func:`njit_loop`, clear the cache (the ``*.nbi`` and
``*.nbc`` files of ``meshladar/weighing/__pycache__``) or loops compiled with the old
options are loaded.
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
