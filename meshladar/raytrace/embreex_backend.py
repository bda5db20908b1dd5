"""The embreex backend: one ray at a time through embreex's ``run`` (the reference),
registered in :data:`meshladar.raytrace.backends.REGISTRY` as "embreex"."""

from __future__ import annotations

from .backends import Backend, register

__all__ = ["build"]


def build(vertices, faces):
    """An embreex scene of float32 vertices (n, 3) and int32 faces (m, 3), robust mode.

    Parameters
    ----------
    vertices : (n, 3) float32 numpy.ndarray
        The triangles' corners, as a :class:`~meshladar.raytrace.backends.Backend`'s
        ``build`` receives them (the engine passes the scene shifted to its centre, at unit
        size).
    faces : (m, 3) int32 numpy.ndarray
        Each triangle's three vertex indices into ``vertices``.

    Returns
    -------
    embreex.rtcore_scene.EmbreeScene
        The scene in robust mode (watertight ray-triangle tests), with one triangle mesh;
        it casts through its ``run(origins, directions, output=, query=)``.

    Raises
    ------
    ImportError
        When embreex is not installed (naming it).
    """
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError as exc:  # pragma: no cover - embreex is a core dependency
        raise ImportError("the mesh model needs embreex: pip install embreex") from exc
    # robust mode: watertight ray-triangle tests, so a ray through a shared edge (the
    # diagonal of a prism's side quad crosses the mid-height slice plane) cannot slip
    # between the two triangles
    raw = rtcore_scene.EmbreeScene(robust=True)
    TriangleMesh(raw, vertices, faces)
    return raw


def available():
    """embreex is a core dependency: always (True, "embreex"); a missing install raises
    ImportError naming it when a scene is built.

    Returns
    -------
    tuple of (bool, str)
        ``(True, "embreex")``.
    """
    return True, "embreex"


register(Backend("embreex", build, available, fused=False, quick_start=True))
