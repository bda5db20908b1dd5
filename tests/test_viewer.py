"""Moved: the viewer's tests are tests/viz/test_pyvista_viewer.py. This module only keeps
``from test_viewer import _SMOKE`` working (tests/test_cli.py, tests/test_notebooks.py)
until they import it from ``_rendering``; it holds no tests."""

from _rendering import _SMOKE  # noqa: F401
