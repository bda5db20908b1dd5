"""meshladar: mesh-based 3D ladar simulation and reflection tomography.

Importing meshladar loads numpy and scipy only. Every public name and submodule is reached
as ``meshladar.<name>`` from one table below and imported on first use (the habit of
scikit-image's lazy package faces), so trimesh, embreex, numba, matplotlib and pyvista load
only with the features that use them. Old module names that moved are deprecated aliases
for one release: they warn with the new name.
"""

from __future__ import annotations

from ._lazy import lazy_attributes as _lazy_attributes

from ._version import __version__

#: public name -> the module that defines it
_NAMES = {
    "SandfordRobertson": "brdf", "Disk": "shapes", "Ellipse": "shapes", "Scene": "scene",
    "Ladar": "ladar", "Sinogram": "sinogram", "simulate": "forward", "fbp": "reconstruct",
    "Image": "images", "log_radiance": "reconstruct", "clip_radiance": "reconstruct",
    "trace": "forward", "weigh": "weighing", "Hits": "hits", "lrcs": "forward.lrcs",
}

#: the public submodules, in layer order (the guide's Layout page), each ``meshladar.<name>``
_SUBMODULES = (
    "errors", "precision", "plotting",
    "brdf", "materials", "shapes", "meshes", "scene", "ladar", "sensor", "motion", "noise",
    "hits", "sinogram", "returns", "waveforms", "images",
    "raytrace", "weighing", "stream", "runs", "io",
    "forward", "scan", "reconstruct", "fit", "studies", "cli",
    "phantoms", "viz",
)

#: moved modules: old name -> new home (each old module warns on import, naming it)
_DEPRECATED = {
    "mesh": "meshes", "results": "io", "receiver": "waveforms",
    "volume": "reconstruct.volumes", "iterative": "reconstruct.iterative",
    "compensation": "reconstruct.compensation", "fitting": "fit", "shapefit": "fit.shapes",
    "resolved": "forward.resolved", "analytic": "forward.analytic", "pixel": "forward.pixel",
    "siddon": "forward.siddon", "refine": "forward.refine", "paper": "studies.paper",
    "peer": "studies.peer", "bench": "studies.bench",
    "study_reconstruction": "studies.reconstruction",
}


__getattr__, __dir__ = _lazy_attributes(__name__, globals(), _NAMES, _SUBMODULES,
                                      _DEPRECATED)


__all__ = ["SandfordRobertson", "Disk", "Ellipse", "Scene", "Ladar", "Sinogram", "simulate",
           "fbp", "Image", "log_radiance", "clip_radiance", "trace", "weigh", "Hits", "lrcs",
           "brdf", "errors", "materials", "__version__"]
