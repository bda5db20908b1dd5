"""Names resolved on first use: a package's heavier names and submodules (PEP 562), and
a module's compiled loops (:func:`deferred_module`), stay unimported until asked for, so
that ``import meshladar`` loads only numpy and scipy and the command line's one-view start
(which calls no compiled loop) does not load numba."""

from __future__ import annotations

import __future__
import importlib

__all__ = ["lazy_attributes", "deferred_module"]


def lazy_attributes(package, namespace, names=(), submodules=(), hidden=()):
    """A package's module-level ``__getattr__`` and ``__dir__``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    namespace : dict
        Its ``globals()``: a name found is put there, so it is looked up once.
    names : dict, optional
        Name → the submodule (relative to the package) that defines it.
    submodules : sequence of str, optional
        Submodules reached as attributes (``meshladar.scan.points``).
    hidden : sequence of str, optional
        Submodules reached as attributes but not listed by ``dir()`` (deprecated aliases).

    Returns
    -------
    __getattr__, __dir__ : callables
        For the package's module body: ``__getattr__, __dir__ = lazy_attributes(...)``.
    """
    names, modules = dict(names), set(submodules) | set(hidden)

    def __getattr__(name):
        if name in names:
            value = getattr(importlib.import_module(f"{package}.{names[name]}"), name)
        elif name in modules:
            value = importlib.import_module(f"{package}.{name}")
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value
        return value

    def __dir__():        # less ``from __future__ import annotations``'s feature object
        own = {n for n, v in namespace.items() if v is not __future__.annotations}
        return sorted(own | set(names) | set(submodules))

    return __getattr__, __dir__


class _DeferredModule:
    """A module's stand-in that imports it at its first attribute lookup (thread-safe:
    Python's import lock; :func:`deferred_module`)."""

    __slots__ = ("_name", "_module")

    def __init__(self, name):
        self._name = name
        self._module = None

    def __getattr__(self, attr):
        if attr in _DeferredModule.__slots__:     # unset (a copy made without __init__)
            raise AttributeError(attr)
        module = self._module
        if module is None:
            module = self._module = importlib.import_module(self._name)
        return getattr(module, attr)

    def __reduce__(self):                         # copied or pickled: a stand-in again
        return deferred_module, (self._name,)

    def __repr__(self):
        return f"<deferred module {self._name!r}>"


def deferred_module(name):
    """A stand-in for the module ``name`` that imports it when one of its attributes is
    first looked up: for a module of compiled loops (numba's), which a small run never
    calls. Where the edge crosses packages, the importer also names the module under
    ``TYPE_CHECKING``, so that the import graph (the layers' check) still holds it.

    Parameters
    ----------
    name : str
        The module's absolute dotted name.

    Returns
    -------
    object
        Its attributes are the module's (looked up in the module at each use, so a test
        that patches the module is seen; patch the module, not the stand-in). Copied or
        pickled, it is a stand-in for the same module.

    Examples
    --------
    >>> from meshladar._lazy import deferred_module
    >>> heavy = deferred_module("json")
    >>> heavy.dumps([1, 2])
    '[1, 2]'
    """
    return _DeferredModule(name)
