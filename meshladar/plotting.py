"""The one door from the engine to :mod:`meshladar.viz`.

Every record's ``.plot()`` delegates here, and no other engine module imports ``viz/``
(the import contract in ``pyproject.toml`` checks it). The drawing module is imported on
first use, so matplotlib stays out of ``import meshladar``, and a missing extra is named.
The habit is pyvista's: its core reaches plotting through one small module only.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys

__all__ = ["plot", "viz", "require"]

#: record class name -> (module of meshladar.viz, function drawing it)
_DRAWERS = {
    "Sinogram": ("quick", "sinogram"),
    "Image": ("quick", "image"),
    "Volume": ("quick", "volume"),
    "Waveforms": ("waveforms", "figure"),
    "ViewDesign": ("fitting", "design_figure"),
    "CrossSection": ("lrcs", "signature"),
}


def plot(record, **options):
    """Draw ``record`` with its quick-look figure from :mod:`meshladar.viz`; returns a
    matplotlib Figure (no pyplot state is touched). ``options`` go to the drawing
    function unchanged.

    Parameters
    ----------
    record : Sinogram, Image, Volume, Waveforms, ViewDesign or CrossSection
        The record to draw, chosen by its class's name: a Sinogram by
        :func:`meshladar.viz.quick.sinogram`, an Image by :func:`meshladar.viz.quick.image`,
        a Volume by :func:`meshladar.viz.quick.volume`, Waveforms by
        :func:`meshladar.viz.waveforms.figure`, a ViewDesign by
        :func:`meshladar.viz.fitting.design_figure` and a CrossSection by
        :func:`meshladar.viz.lrcs.signature`.
    **options
        Keyword arguments of that function.

    Returns
    -------
    matplotlib.figure.Figure
        The drawing function's figure.

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
    paper's, the studies', the viewer), imported on first use; a missing extra is named.

    Parameters
    ----------
    module : str
        The module's name under ``meshladar.viz``: ``"quick"``, ``"paper"``,
        ``"studies"``, ``"viewer"``, ``"bounce_view"``, ``"points"``, ``"waveforms"``,
        ``"fitting"``, ``"resolved"``, ``"lrcs"`` or ``"style"``.

    Returns
    -------
    module
        ``meshladar.viz.<module>``.

    Raises
    ------
    ImportError
        When it cannot be imported (matplotlib or pyvista absent, or no such module),
        naming the ``viz`` extra.
    """
    try:
        return importlib.import_module(f"meshladar.viz.{module}")
    except ImportError as exc:  # matplotlib or pyvista absent
        raise ImportError("plotting needs the viz extra: pip install 'meshladar[viz]'"
                          ) from exc


#: What each drawing package is needed for, in the message that names the extra.
_NEEDS = {"matplotlib": "figures need matplotlib", "pyvista": "the viewer needs pyvista"}


def require(package: str) -> None:
    """Raise the one-line ImportError naming the ``viz`` extra when ``package``
    (matplotlib or pyvista) cannot be imported: the command line calls it before any work,
    so a plain install does not compute for minutes and then fail on the figure.

    Parameters
    ----------
    package : {"matplotlib", "pyvista"}
        The drawing package needed. It is looked up (already imported, or found by
        ``importlib.util.find_spec``), not imported.

    Raises
    ------
    ValueError
        When ``package`` is neither.
    ImportError
        When ``package`` cannot be found: "figures need matplotlib" or "the viewer needs
        pyvista", with ``pip install 'meshladar[viz]'``.
    """
    if package not in _NEEDS:
        raise ValueError(f"package must be one of {tuple(_NEEDS)}; got {package!r}")
    try:
        found = sys.modules[package] is not None if package in sys.modules \
            else importlib.util.find_spec(package) is not None
    except (ImportError, ValueError):
        found = False
    if not found:
        raise ImportError(f"{_NEEDS[package]}: pip install 'meshladar[viz]'")
