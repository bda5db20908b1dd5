"""Attributes of a package resolved on first use (PEP 562): its heavier names and
submodules stay unimported until asked for, so that ``import meshladar`` and the command
line's one-view start load only numpy and scipy."""

from __future__ import annotations

import importlib

__all__ = ["lazy_attributes"]


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

    def __dir__():
        return sorted(set(namespace) | set(names) | set(submodules))

    return __getattr__, __dir__
