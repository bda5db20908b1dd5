"""The ray-casting backends, chosen from a registry (no ``if backend == ...`` chains).

Each backend module fills :data:`REGISTRY` with a :class:`Backend` when it is imported:
:mod:`.packets` (coherent Embree 4 packets through ctypes and numba; as "raster", the
same with a dense orthographic view's first hits drawn into a depth buffer) and
:mod:`.embreex_backend` (embreex, one ray at a time: the reference) and
:mod:`.warp_backend` (NVIDIA Warp's ray queries, on a CUDA device or the CPU). A new
backend is a module that calls :func:`register`; :data:`BUILTIN` names the modules loaded
on first use, so numba, embreex and Warp load only when a ray is cast."""

from __future__ import annotations

import importlib
import warnings
from dataclasses import dataclass
from typing import Callable

from .._validate import check_choice
from ..errors import MeshladarWarning, ParameterError, user_stacklevel

__all__ = ["BACKENDS", "Backend", "REGISTRY", "register", "backend", "choices",
           "resolve_backend"]

#: The ``backend=`` choices; "auto" takes the first of :data:`PREFERENCE` that loads.
BACKENDS = ("auto", "packets", "raster", "embreex", "warp", "warp-cpu")
#: "auto"'s order of preference: a CUDA device through Warp where there is one (an
#: optional backend: passed over in silence where it cannot load), then the packets with
#: dense orthographic views drawn ("raster"), then the packets alone.
PREFERENCE = ("warp", "raster", "packets", "embreex")
#: The built-in backends' modules, imported on first use (they register themselves).
BUILTIN = {"packets": "meshladar.raytrace.packets",
           "raster": "meshladar.raytrace.packets",
           "embreex": "meshladar.raytrace.embreex_backend",
           "warp": "meshladar.raytrace.warp_backend",
           "warp-cpu": "meshladar.raytrace.warp_backend"}


@dataclass(frozen=True)
class Backend:
    """One way to cast rays.

    ``build(vertices, faces)`` makes a raw scene of float32 (n, 3) vertices at unit size and
    int32 (m, 3) faces, with embreex's ``run(origins, directions, output=, query=)``
    interface; ``available()`` says (True, where) or (False, why); ``fused`` whether the
    weigh stage's fused loop (:mod:`meshladar.weighing.fused`) can cast with its scenes;
    ``optional`` whether "auto" passes over it in silence when it cannot load (hardware
    that may be absent); ``quick_start`` whether a small run on it is weighed in numpy
    (embreex's, which casts without numba).

    Attributes
    ----------
    name : str
        The backend's name, its key in :data:`REGISTRY` and its ``backend=`` choice.
    build : callable
        ``build(vertices, faces)``: the raw scene of float32 (n, 3) vertices (at unit size)
        and int32 (m, 3) faces, an object with embreex's ``run(origins, directions,
        output=, query=)``.
    available : callable
        ``available()``: ``(True, where)`` when the backend loads here, else
        ``(False, why)``.
    fused : bool
        Whether the fused cast-weigh-bin loop can cast with its scenes (default False).
    optional : bool
        Whether "auto" skips it without a warning when it cannot load (default False).
    quick_start : bool
        Whether a run on it of at most :data:`meshladar.forward.job.QUICK_RAYS` rays is
        weighed in numpy, so that it calls none of numba's compiled loops (default False).
    """

    name: str
    build: Callable
    available: Callable
    fused: bool = False
    optional: bool = False
    quick_start: bool = False


#: Backends by name, filled by the backend modules themselves.
REGISTRY: dict = {}


def register(entry: Backend) -> Backend:
    """Add (or replace) a backend in :data:`REGISTRY`; returns it.

    Parameters
    ----------
    entry : Backend
        The backend, registered under ``entry.name`` (an existing entry of that name is
        replaced; nothing is checked).

    Returns
    -------
    Backend
        ``entry`` itself.
    """
    REGISTRY[entry.name] = entry
    return entry


def backend(name: str) -> Backend:
    """The registered backend ``name``, its module imported on first use.

    Parameters
    ----------
    name : str
        A registered backend's name, or a built-in one (:data:`BUILTIN`: ``"packets"``,
        ``"raster"``, ``"embreex"``, ``"warp"``, ``"warp-cpu"``), whose module is imported
        (and registers itself) here. ``"auto"`` is not a backend: :func:`resolve_backend`
        chooses one for it.

    Returns
    -------
    Backend
        The entry of :data:`REGISTRY`. Whether it can load here is not checked (its
        ``available()`` says).

    Raises
    ------
    ParameterError
        When ``name`` is neither registered nor built in.
    """
    if name not in REGISTRY and name in BUILTIN:
        importlib.import_module(BUILTIN[name])
    if name not in REGISTRY:
        raise ParameterError(f"backend must be one of {tuple(REGISTRY) or PREFERENCE}; "
                             f"got {name!r}")
    return REGISTRY[name]


def choices() -> tuple:
    """The ``backend=`` names: "auto", the built-in backends and any registered one.

    Returns
    -------
    tuple of str
        ``"auto"``, then the built-in names (:data:`BUILTIN`, in order), then any other
        registered name, each once.
    """
    return ("auto",) + tuple(dict.fromkeys((*BUILTIN, *REGISTRY)))


_FALLBACK_SAID = False


def resolve_backend(name):
    """The backend a run uses, by name: ``name`` itself when it loads, "auto" the first of
    :data:`PREFERENCE` that loads (warning once per process when it falls back).

    Parameters
    ----------
    name : str
        One of :func:`choices`: ``"auto"``, a built-in backend's name (``"packets"``,
        ``"raster"``, ``"embreex"``, ``"warp"``, ``"warp-cpu"``) or a registered one's.

    Returns
    -------
    str
        The name of a backend whose ``available()`` is true here: ``name`` itself, or for
        ``"auto"`` the first of :data:`PREFERENCE` (``"warp"`` where a CUDA device is
        present, then ``"raster"`` (the packets, dense orthographic views drawn), then
        ``"packets"``, then ``"embreex"``).

    Raises
    ------
    ParameterError
        When ``name`` is not one of :func:`choices`; when a backend named explicitly cannot
        load here (the message gives its reason); when, under ``"auto"``, none of
        :data:`PREFERENCE` loads.

    Warns
    -----
    MeshladarWarning
        Under ``"auto"``, when a preferred backend that is not optional cannot load and a
        later one is used (once per process).
    """
    global _FALLBACK_SAID
    check_choice("backend", name, choices())
    why = None
    for candidate in (PREFERENCE if name == "auto" else (name,)):
        ok, reason = backend(candidate).available()
        if ok:
            if why is not None and not _FALLBACK_SAID:
                _FALLBACK_SAID = True
                warnings.warn(f"the packet backend cannot load ({why}): the mesh engine "
                              "casts with embreex, one ray at a time (backend='embreex'); "
                              "the numbers are the same, slower", MeshladarWarning,
                              stacklevel=user_stacklevel())
            return candidate
        if name != "auto":
            raise ParameterError(f"backend={name!r} cannot load here ({reason}); use "
                                 "backend='embreex' or 'auto'")
        if not backend(candidate).optional:
            why = reason
    raise ParameterError(f"no ray-casting backend loads here ({why})")
