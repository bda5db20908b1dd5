"""Everything that draws: matplotlib figures and the pyvista 3-D viewer.

Installed as ``meshladar.viz`` (the ``viz`` extra: matplotlib, pyvista). Its modules:
:mod:`~meshladar.viz.quick` (the records' quick looks), :mod:`~meshladar.viz.waveforms`,
:mod:`~meshladar.viz.resolved`, :mod:`~meshladar.viz.lrcs` and :mod:`~meshladar.viz.fitting`
(figures of waveforms, resolved returns, cross sections and view designs),
:mod:`~meshladar.viz.paper` (the paper's Figs 5-11), :mod:`~meshladar.viz.studies` (the
studies' figures), :mod:`~meshladar.viz.viewer`, :mod:`~meshladar.viz.bounce_view` and
:mod:`~meshladar.viz.points` (the 3-D viewer: scenes, bounces, point clouds) and
:mod:`~meshladar.viz.style` (the one figure style).

The engine reaches it only through :mod:`meshladar.plotting`, which imports a drawing
module on first use: every record's ``.plot()`` and the command line's figures go through
it, so ``import meshladar`` imports neither matplotlib nor pyvista.
"""

__all__: list[str] = []
