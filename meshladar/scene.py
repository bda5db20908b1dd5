"""Scenes: analytic shapes (:mod:`meshladar.shapes`) or triangle meshes, a coating each.

Shapes in one scene must not overlap (touching is allowed): the boundary of a union of
overlapping shapes is not the union of their boundaries, so overlapping shapes raise
:class:`~meshladar.errors.GeometryError`.
"""

from __future__ import annotations

import warnings
from functools import cached_property

import numpy as np

from ._scene_inputs import (checked_coatings, checked_shapes, parts_by_face, parts_by_name,
                            parts_of_items)
from ._summary import scene_summary, table, text
from ._validate import check_real
from .errors import MeshladarWarning, ParameterError, user_stacklevel
from .meshes import convex_hull, inspect_parts, load_parts, prism
from .meshes.visibility import Visibility, scene_visibility
from ._extents import HULL_MIN_VIEWS, circle_about_box, point_ranges, shape_ranges
from .precision import OVERLAP_RTOL
from .shapes import Disk, Ellipse, Shape

__all__ = ["Shape", "Disk", "Ellipse", "Scene", "OVERLAP_RTOL", "HULL_MIN_VIEWS"]


class Scene:
    """A set of non-overlapping analytic shapes, or of triangle meshes, each with a coating.

    Mesh scenes come from :meth:`from_mesh`, :meth:`from_meshes` or :meth:`tessellate`;
    they hold ``parts`` (MeshPart), ``materials`` and a ``report`` of the mesh checks.

    Parameters
    ----------
    shapes : sequence of Disk or Ellipse
        At least one. Shapes may touch but not overlap (GeometryError).

    Raises
    ------
    ParameterError
        When ``shapes`` is not a sequence, is empty, or holds something other than a Disk
        or an Ellipse.
    GeometryError
        When two shapes overlap.

    Examples
    --------
    >>> import meshladar as ml
    >>> scene = ml.Scene([ml.Disk(center=(0.0, 0.0), radius=0.8,
    ...                           material=ml.materials.DARK_GRAY)])
    """

    _parts: tuple = ()
    _materials: tuple = ()
    _report: dict = {}

    def __init__(self, shapes):
        self._shapes = checked_shapes(shapes)

    @property
    def shapes(self) -> tuple[Shape, ...]:
        """The analytic shapes (empty for a mesh scene)."""
        return self._shapes

    @property
    def is_mesh(self) -> bool:
        return bool(self._parts)

    @property
    def parts(self):
        """The mesh parts (empty for an analytic scene)."""
        return self._parts

    @property
    def materials(self) -> tuple:
        """The coatings: one per shape, or the mesh scene's material list."""
        return self._materials if self._parts else tuple(s.material for s in self._shapes)

    @property
    def report(self) -> dict:
        """Mesh checks: degenerate faces dropped, watertight and inverted parts, faces."""
        return dict(self._report)

    # -- mesh scenes ------------------------------------------------------------------------
    @classmethod
    def _from_parts(cls, parts, materials, shapes=()):
        mats = checked_coatings(parts, materials)
        cleaned, report = inspect_parts(parts)
        inverted = [p.name for p, bad in zip(cleaned, report["inverted"]) if bad]
        if inverted:
            n = report["inverted_bodies"]
            warnings.warn(f"{n} closed bod{'y' if n == 1 else 'ies'} with inverted normals "
                          f"(faces wound clockwise seen from outside), in part "
                          f"{inverted[0]!r}{' and others' if len(inverted) > 1 else ''}: "
                          "traced two-sided by default, but back_faces='ignore' would blank "
                          "them (scene.report['inverted'])", MeshladarWarning, stacklevel=user_stacklevel())
        self = cls.__new__(cls)
        self._shapes = tuple(shapes)
        self._parts = tuple(cleaned)
        self._materials = mats
        self._report = report
        return self

    @classmethod
    def from_parts(cls, parts, materials):
        """A mesh scene from :class:`meshladar.meshes.MeshPart` objects (e.g.
        ``meshladar.meshes.sphere(center, radius, 0, subdivisions=5)``) and their materials.

        Parameters
        ----------
        parts : iterable of meshladar.meshes.MeshPart
            The mesh parts; each face's material index points into ``materials``.
            Degenerate faces are dropped (counted in ``report``).
        materials : list or tuple of BRDF
            The coatings, indexed by the parts' face material indices.

        Returns
        -------
        Scene
            A mesh scene of the cleaned parts.

        Raises
        ------
        ParameterError
            When ``materials`` is not a list or tuple, a material is not a BRDF, a part is
            not a MeshPart, or a face material index is outside [0, len(materials) − 1].
        ModelError
            When a material lacks a method the BRDF protocol needs.
        GeometryError
            When no part has a face left (all degenerate or none given).

        Warns
        -----
        MeshladarWarning
            When some closed body has inverted normals (faces wound inward).
        """
        return cls._from_parts(list(parts), materials)

    @classmethod
    def from_mesh(cls, mesh_or_path, material=None, *, materials=None, face_materials=None,
                  transform=None):
        """A scene from anything trimesh loads: STL, OBJ, PLY, OFF, GLB/GLTF with parts, zip
        and tar archives, .gz/.bz2/.xz files, 3MF and DAE with their optional readers (see
        :func:`meshladar.meshes.load_parts`). Only vertices, faces and part names are read;
        vertices at the same position are merged (UV seams are not creases). The scene is a
        3-D target: ``simulate(..., model="mesh")`` returns all of it.

        Raises GeometryError (one line naming the file) for a file that is not a triangle
        mesh: empty, junk, a point cloud, a 2-D drawing, a format whose reader is missing.

        Parameters
        ----------
        mesh_or_path : trimesh.Trimesh, trimesh.Scene, meshladar.meshes.TriangleMesh or path
        material : BRDF, optional
            The coating of every part (unless ``materials`` names a part's own).
        materials : dict, optional
            Coating per part name (GLB/GLTF node names, OBJ object names); parts not named
            take ``material``.
        face_materials : (n_faces,) int, optional
            Per-face index into ``materials`` given as a list (single-mesh input only).
        transform : (4, 4) array, optional
            Applied to every part.

        Returns
        -------
        Scene
            A mesh scene: one part per mesh the file holds, the coatings in ``materials``
            (each distinct coating once, in the parts' order; with ``face_materials`` the
            list given).

        Raises
        ------
        GeometryError
            For a file or object that is not a triangle mesh (see
            :func:`meshladar.meshes.load_parts`), or when no face is left.
        ParameterError
            When ``face_materials`` is given for several parts, without ``materials`` as a
            list, or not as (n_faces,) integers; when ``materials`` is neither a dict nor
            None without ``face_materials``, or names a part the file lacks; when a part
            has no coating; when ``transform`` is not a finite 4 × 4 matrix; or when a
            coating is not a BRDF.

        Warns
        -----
        MeshladarWarning
            When some closed body has inverted normals.
        """
        loaded = load_parts(mesh_or_path)
        if face_materials is not None:
            parts, mats = parts_by_face(loaded, materials, face_materials, transform)
        else:
            parts, mats = parts_by_name(loaded, material, materials, transform)
        return cls._from_parts(parts, mats)

    @classmethod
    def from_meshes(cls, items):
        """A scene of several meshes: items of (mesh_or_path, material) or
        (mesh_or_path, material, transform).

        Parameters
        ----------
        items : iterable of tuple
            ``(mesh_or_path, material)`` or ``(mesh_or_path, material, transform)``:
            anything :func:`meshladar.meshes.load_parts` takes, its coating (a BRDF) and an
            optional (4, 4) transform applied to its parts. Parts are named
            ``"<k>:<part name>"``, k the item's index.

        Returns
        -------
        Scene
            A mesh scene of every item's parts, each distinct coating once in
            ``materials``.

        Raises
        ------
        ParameterError
            When an item is not a 2- or 3-tuple (or list), a transform is not a finite
            4 × 4 matrix, or a coating is not a BRDF.
        GeometryError
            For an item that is not a triangle mesh, or when no face is left.

        Warns
        -----
        MeshladarWarning
            When some closed body has inverted normals.
        """
        parts, mats = parts_of_items(items)
        return cls._from_parts(parts, mats)

    def tessellate(self, segments=256, *, height=1.0, z0=0.0):
        """This analytic scene as a mesh scene: each disk/ellipse extruded to a prism of
        ``height`` centred on z = z0 with ``segments`` boundary vertices. The parts keep the
        shapes' exact normals (``normals="exact"`` when tracing).

        Parameters
        ----------
        segments : int
            Boundary vertices per shape, ≥ 3 (default 256), spaced uniformly in the
            eccentric angle.
        height : float
            Height of each prism, scene units, > 0 (default 1.0). Keyword-only.
        z0 : float
            z of the prisms' mid-plane, scene units (default 0.0). Keyword-only.

        Returns
        -------
        Scene
            A mesh scene (one part per shape, the same materials) that keeps the analytic
            shapes.

        Raises
        ------
        ParameterError
            When this scene is already a mesh, ``height`` or ``z0`` is out of range or not
            finite, ``segments`` is not an integer ≥ 3, or the prisms would pass
            meshladar's allocation cap.
        """
        if self.is_mesh:
            raise ParameterError("tessellate needs an analytic scene; this one is a mesh")
        height = check_real("height", height, low=0.0, low_open=True)
        z0 = check_real("z0", z0)
        mats = list(self.materials)
        parts = [prism(s, segments, height, i, z0=z0) for i, s in enumerate(self._shapes)]
        return Scene._from_parts(parts, mats, shapes=self._shapes)

    def __len__(self) -> int:
        return len(self._parts) if self._parts else len(self._shapes)

    def __iter__(self):
        return iter(self._parts if self._parts else self._shapes)

    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds of a mesh scene (min, max).

        Returns
        -------
        (2, 3) numpy.ndarray
            Row 0 the smallest x, y, z of any vertex, row 1 the largest; scene units.

        Raises
        ------
        ParameterError
            For an analytic scene (use :meth:`bounding_circle`).
        """
        if not self._parts:
            raise ParameterError("bounds() is for mesh scenes; use bounding_circle()")
        return np.stack([self._vertices.min(axis=0), self._vertices.max(axis=0)])

    def hull_points(self) -> np.ndarray:
        """(k, 3) vertices of the convex hull of a mesh scene (all vertices when the hull is
        degenerate: a flat sheet; for meshes of more than 200,000 points on their hull, a
        superset of them), computed once per mesh. Every extreme of a linear function of
        position (a range, a ray grid's extent) is attained at one of them.

        Returns
        -------
        (k, 3) numpy.ndarray
            The hull's vertices, scene units.

        Raises
        ------
        ParameterError
            For an analytic scene.
        """
        if not self._parts:
            raise ParameterError("hull_points() is for mesh scenes")
        return self._hull

    def cached(self, key, make):
        """``make()``, computed once per scene and ``key``: what the engine derives from a
        scene's parts (traced geometry, curvature estimates) stays true, as a Scene is
        immutable.

        Parameters
        ----------
        key : hashable
            What is derived (the cache's key).
        make : callable
            Called with no arguments, the first time ``key`` is asked for only.

        Returns
        -------
        object
            What ``make()`` returned the first time for this ``key``.
        """
        derived = self.__dict__.setdefault("_derived", {})
        if key not in derived:
            derived[key] = make()
        return derived[key]

    def visibility(self) -> Visibility:
        """Which parts can send light to which, once per scene (exact where a part cannot
        see itself: flat, or closed and convex; :mod:`meshladar.meshes.visibility`).

        Returns
        -------
        Visibility
            ``sees`` (n, n) bool, ``convex`` per part, ``needs_bounces``.
        """
        return self.cached("visibility", lambda: scene_visibility(
            [p.name for p in self._parts], self._parts, self._report.get("bodies"))
            if self._parts else scene_visibility(
            [s.name or f"shape {i}" for i, s in enumerate(self._shapes)]))

    def support_points(self, n_views=None) -> np.ndarray:
        """(k, 3) points of a mesh scene among which every extreme of a linear (or, from a
        point outside the mesh, perspective) function of position is attained, for
        ``n_views`` views: the hull's vertices (:meth:`hull_points`) when known already or
        the views are many (≥ ``HULL_MIN_VIEWS``, 512), else every vertex (the same
        extremes; a hull costs as much as thousands of projections of every vertex).

        Parameters
        ----------
        n_views : int, optional
            How many views the points will serve. Default None: as many as make the hull
            worth building.

        Returns
        -------
        (k, 3) numpy.ndarray
            The points, scene units (a view of the scene's own arrays: not to be written).

        Raises
        ------
        ParameterError
            For an analytic scene.
        """
        if not self._parts:
            raise ParameterError("support_points() is for mesh scenes")
        if "_hull" in self.__dict__ or n_views is None or n_views >= HULL_MIN_VIEWS:
            return self._hull
        return self._vertices

    @cached_property
    def _vertices(self) -> np.ndarray:
        return np.concatenate([p.vertices for p in self._parts])

    @cached_property
    def _hull(self) -> np.ndarray:
        if len(self._parts) == 1:       # the part's own: shared by every scene of it
            return self._parts[0].hull_points
        return convex_hull(self._vertices)

    def view_ranges(self, view_vectors) -> tuple[np.ndarray, np.ndarray]:
        """(nearest, farthest) range r = −p·w of the scene in each view, two (n_views,)
        arrays (range zero is the plane through the world origin perpendicular
        to w, growing away from the ladar).

        Parameters
        ----------
        view_vectors : (n_views, 3) array_like
            Unit view vectors w (from the scene toward the ladar; not normalised here). An
            analytic scene uses their x and y components only.

        Returns
        -------
        nearest, farthest : (n_views,) numpy.ndarray
            The smallest and largest range of the scene in each view, scene units: over
            its :meth:`support_points` for a mesh scene, over the shapes' exact boundaries
            for an analytic one.
        """
        w = np.asarray(view_vectors, dtype=np.float64).reshape(-1, 3)
        if self._parts:
            return point_ranges(self.support_points(len(w)), w)
        return shape_ranges(self._shapes, w)

    def range_span(self, view_vectors) -> tuple[float, float]:
        """(nearest, farthest) range any point of the scene takes over all the views.

        Parameters
        ----------
        view_vectors : (n_views, 3) array_like
            Unit view vectors w, as for :meth:`view_ranges`.

        Returns
        -------
        nearest, farthest : float
            The smallest and largest range over every view, scene units.
        """
        lo, hi = self.view_ranges(view_vectors)
        return float(lo.min()), float(hi.max())

    def bounding_circle(self) -> tuple[tuple[float, float], float]:
        """A circle (centre, radius) in x-y containing every shape (about their box centre).

        Returns
        -------
        centre : tuple of float
            (x, y) of the centre of the shapes' bounding box (for a mesh scene without
            analytic shapes, of the vertices' x-y bounds), scene units.
        radius : float
            The smallest radius about that centre that holds every shape's bounding circle
            (every vertex, for a mesh scene), scene units.
        """
        if self._parts and not self._shapes:
            return circle_about_box(self._vertices[:, :2], np.zeros(len(self._vertices)))
        return circle_about_box(np.array([s.center for s in self._shapes]),
                                np.array([s.bounding_radius for s in self._shapes]))

    def _summary(self):
        return scene_summary(self)

    def __repr__(self) -> str:
        return text("Scene", *self._summary())

    def _repr_html_(self) -> str:
        return table("Scene", *self._summary())
