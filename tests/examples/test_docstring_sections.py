"""Every public definition's docstring has its numpydoc sections (the API reference is made
from them).

The public definitions: the functions and classes each public module (no ``_`` in its
dotted name) lists in ``__all__`` and defines, or re-exports from a private module, and
the public methods those classes define themselves.
A function or method that takes parameters (``self`` and ``cls`` apart) needs a
``Parameters`` section; one whose body returns a value needs ``Returns`` (``Yields`` for a
generator). A class needs ``Parameters`` or ``Attributes`` when it is built from
arguments. Properties and dunder methods are documented by their one line.

Run as a script, it prints the missing sections under the paths given
(``python tests/examples/test_docstring_sections.py meshladar/reconstruct``).
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pathlib
import sys
import textwrap
import warnings

ROOT = pathlib.Path(__file__).resolve().parents[2]
#: The public packages: the engine, and the phantom library and viewer it installs.
PACKAGES = {"meshladar": ROOT / "meshladar", "meshladar.phantoms": ROOT / "phantoms",
            "meshladar.viz": ROOT / "viz"}


def _modules():
    for dotted, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            if any(p.startswith("_") for p in parts):
                continue
            yield ".".join([dotted, *parts]), path


def _sections(doc):
    lines = inspect.cleandoc(doc or "").splitlines()
    return {a.strip() for a, b in zip(lines, lines[1:])
            if b.strip() and set(b.strip()) == {"-"} and len(b.strip()) >= 3}


def _returns_value(fn):
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    except (OSError, TypeError, SyntaxError):
        return False, False
    top = tree.body[0]
    nested = {id(n) for d in ast.walk(top) if d is not top
              and isinstance(d, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
              for n in ast.walk(d)}
    own = [n for n in ast.walk(top) if id(n) not in nested]
    gen = any(isinstance(n, (ast.Yield, ast.YieldFrom)) for n in own)
    ret = any(isinstance(n, ast.Return) and n.value is not None
              and not (isinstance(n.value, ast.Constant) and n.value.value is None)
              for n in own)
    return ret, gen


def _takes_parameters(fn):
    try:
        params = list(inspect.signature(fn).parameters)
    except (TypeError, ValueError):
        return False
    return bool([p for p in params if p not in ("self", "cls")])


def _function_missing(fn):
    have = _sections(fn.__doc__)
    need = []
    if _takes_parameters(fn) and "Parameters" not in have:
        need.append("Parameters")
    ret, gen = _returns_value(fn)
    if gen and "Yields" not in have:
        need.append("Yields")
    elif ret and not gen and "Returns" not in have:
        need.append("Returns")
    return need


def _class_missing(cls):
    have = _sections(cls.__doc__)
    init = cls.__dict__.get("__init__")
    built = _takes_parameters(cls) if init is not None or hasattr(
        cls, "__dataclass_fields__") else False
    if built and not have & {"Parameters", "Attributes"}:
        return ["Parameters or Attributes"]
    return []


def _public_methods(cls):
    for name, member in vars(cls).items():
        if name.startswith("_") or isinstance(member, property):
            continue
        fn = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
        if inspect.isfunction(fn):
            yield name, fn


def _current(get):
    """``get()``, or None for a deprecated alias (a moved module or name warns when reached:
    it is documented at its new home)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        try:
            return get()
        except DeprecationWarning:
            return None


def _defined_for(obj, dotted):
    """Whether ``dotted`` is where ``obj`` is public: it defines it, or re-exports it from a
    private module (``meshladar._pulses.GaussianPulse`` is public as
    ``meshladar.waveforms.GaussianPulse``)."""
    home = getattr(obj, "__module__", None) or ""
    return home == dotted or (home.startswith("meshladar.")
                              and any(p.startswith("_") for p in home.split(".")[1:]))


def missing(paths=None):
    """{"module.name": [sections]} of every public definition under ``paths`` (files or
    folders; default all) that lacks a section."""
    chosen = [pathlib.Path(p).resolve() for p in paths or []]
    out, seen = {}, set()
    for dotted, path in _modules():
        if chosen and not any(path == c or c in path.parents for c in chosen):
            continue
        module = _current(lambda: importlib.import_module(dotted))
        for name in getattr(module, "__all__", ()) if module is not None else ():
            obj = _current(lambda: getattr(module, name, None))
            if not (inspect.isfunction(obj) or inspect.isclass(obj)) \
                    or not _defined_for(obj, dotted) or id(obj) in seen:
                continue
            seen.add(id(obj))
            label = f"{dotted}.{obj.__qualname__}"
            need = _function_missing(obj) if inspect.isfunction(obj) else _class_missing(obj)
            if need:
                out[label] = need
            if inspect.isclass(obj):
                for mname, fn in _public_methods(obj):
                    need = _function_missing(fn)
                    if need:
                        out[f"{label}.{mname}"] = need
    return out


def test_every_public_definition_has_its_sections():
    found = missing()
    assert not found, ("public definitions without their numpydoc sections:\n"
                       + "\n".join(f"  {n}: {', '.join(v)}" for n, v in sorted(found.items())))


def test_the_check_sees_what_is_missing():
    """The checker is not blind: a function with an argument and a return and no sections,
    and a dataclass without Attributes, are each caught; with the sections they pass."""
    def bare(x):
        """One line."""
        return x

    def documented(x):
        """One line.

        Parameters
        ----------
        x : float

        Returns
        -------
        float
        """
        return x

    def gen(n):
        """One line.

        Parameters
        ----------
        n : int
        """
        yield n

    assert _function_missing(bare) == ["Parameters", "Returns"]
    assert _function_missing(documented) == []
    assert _function_missing(gen) == ["Yields"]
    from dataclasses import dataclass

    @dataclass
    class Record:
        """One line."""
        a: int

    assert _class_missing(Record) == ["Parameters or Attributes"]
    # a public name re-exported from a private module is checked where it is public
    from meshladar import _pulses, waveforms
    assert _defined_for(_pulses.GaussianPulse, "meshladar.waveforms")
    assert waveforms.GaussianPulse is _pulses.GaussianPulse
    assert not _defined_for(inspect.signature, "meshladar.io")


if __name__ == "__main__":
    for label, need in sorted(missing(sys.argv[1:]).items()):
        print(f"{label}: {', '.join(need)}")
