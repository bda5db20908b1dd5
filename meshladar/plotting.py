"""The one door from the engine to :mod:`meshladar.viz`.

Every record's ``.plot()`` delegates here, and no other engine module imports ``viz/``
(the import contract in ``pyproject.toml`` checks it). The drawing module is imported on
first use, so matplotlib stays out of ``import meshladar``, and a missing extra is named.
The habit is pyvista's: its core reaches plotting through one small module only.
"""

from __future__ import annotations

import importlib

__all__ = ["plot", "viz"]

#: record class name -> (module of meshladar.viz, function drawing it)
_DRAWERS = {
    "Sinogram": ("quick", "sinogram"),
    "Image": ("quick", "image"),
    "Volume": ("quick", "volume"),
    "Waveforms": ("waveforms", "figure"),
    "ViewDesign": ("fitting", "design_figure"),
}


def plot(record, **options):
    """Draw ``record`` with its quick-look figure from :mod:`meshladar.viz`; returns a
    matplotlib Figure (no pyplot state is touched). ``options`` go to the drawing
    function unchanged.

    Raises
    ------
    TypeError
        For a record that has no quick look.
    ImportError
        When the ``viz`` extra (matplotlib, pyvista) is not installed.
    """
    kind = type(record).__name__
    if kind not in _DRAWERS:
        raise TypeError(f"no quick look for a {kind}; records with one: "
                        f"{tuple(sorted(_DRAWERS))}")
    module, name = _DRAWERS[kind]
    return getattr(viz(module), name)(record, **options)


def viz(module: str):
    """The drawing module ``meshladar.viz.<module>`` (the command line's figures: the
    paper's, the studies', the viewer), imported on first use; a missing extra is named."""
    try:
        return importlib.import_module(f"meshladar.viz.{module}")
    except ImportError as exc:  # matplotlib or pyvista absent
        raise ImportError("plotting needs the viz extra: pip install 'meshladar[viz]'"
                          ) from exc
