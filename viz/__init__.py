"""Everything that draws: matplotlib figures of the paper and studies, the pyvista viewer.

Installed as ``meshladar.viz``. It may import matplotlib and pyvista; the engine
(``meshladar``) never imports it. The figures and the viewer arrive with the
reconstruction and viewer work; this package is the place they live.
"""

__all__: list[str] = []
