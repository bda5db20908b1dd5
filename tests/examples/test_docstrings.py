"""Every ``>>>`` example in meshladar's docstrings runs and prints what it shows.

Each module under ``meshladar/`` whose source holds ``>>>`` is one test case: doctest runs
all of its examples (ELLIPSIS and NORMALIZE_WHITESPACE), with warnings as errors like the
rest of the suite. A module added with an example is collected by itself.
"""

from __future__ import annotations

import doctest
import importlib
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "meshladar"


def _module_name(path):
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = sorted(_module_name(p) for p in PACKAGE.rglob("*.py")
                 if ">>>" in p.read_text(encoding="utf-8"))


def test_examples_are_found():
    """The collection sees the docstrings' examples (one that saw none would pass)."""
    assert {"meshladar.ladar", "meshladar.forward", "meshladar.forward.mesh"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    tests = [t for t in doctest.DocTestFinder().find(module, name) if t.examples]
    assert tests, f"{name}: '>>>' in the source but no example found by doctest"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in tests:
        runner.run(t, out=lambda s: None)
    failed = runner.summarize(verbose=False).failed
    if failed:                        # rerun to report the failures with their output
        report = []
        for t in tests:
            doctest.DocTestRunner(optionflags=runner.optionflags).run(t, out=report.append)
        pytest.fail(f"{name}: {failed} example(s) failed:\n" + "".join(report)[-4000:])
