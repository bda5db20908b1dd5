"""meshladar: mesh-based 3D ladar simulation and reflection tomography.

Importing meshladar loads numpy and scipy only; trimesh, embreex, matplotlib and pyvista
are imported lazily by the features that use them.
"""

from __future__ import annotations

from . import brdf, errors, materials
from .brdf import SandfordRobertson
from .forward import simulate
from .ladar import Ladar
from .reconstruct import Image, clip_radiance, fbp, log_radiance
from .scene import Scene
from .shapes import Disk, Ellipse
from .sinogram import Sinogram
from .raytrace import Hits, trace
from .weighing import weigh

__version__ = "0.1.0"

_LAZY_SUBPACKAGES = ("phantoms", "viz", "mesh", "studies", "results", "siddon", "stream",
                     "runs", "refine", "bench", "paper")


def __getattr__(name):
    # The phantom library, the viewer and the heavier engine modules are reached as
    # meshladar.<name> but imported only on first use, so `import meshladar` stays light.
    if name in _LAZY_SUBPACKAGES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = ["SandfordRobertson", "Disk", "Ellipse", "Scene", "Ladar", "Sinogram", "simulate",
           "fbp", "Image", "log_radiance", "clip_radiance", "trace", "weigh", "Hits",
           "brdf", "errors", "materials", "__version__"]
