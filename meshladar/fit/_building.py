"""A coating kernel built from the geometry: the fields of a
:class:`~meshladar.fit.kernels.CoatingKernel` (as keywords) from analytic shapes, from mesh
hits, or from a mesh scene traced here.

* Analytic shapes: each boundary cut per view into ``samples`` pieces, every piece's
  visible part split between bins exactly (:mod:`._sampling`), its weight interpolated
  cubically on the tables' θ grid.
* Mesh hits: each hit binned at its range with the weight :func:`~meshladar.weigh` gives
  it, per material index, interpolated linearly on the θ grid.
* A mesh scene: traced with :func:`meshladar.trace` at ``rays_per_bin`` rays per bin width,
  then binned as hits; the scene is kept, so the kernel can be traced again at another
  count.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..forward.mesh import trace
from ..scene import Scene
from ..weighing import per_table_weight
from ._sampling import analytic_triplets, interp_matrix
from ._tables import GRID


def parts_of(geometry):
    """(part names, coatings) of the kernel of ``geometry`` (an analytic or mesh Scene, or
    Hits), known before it is traced: an analytic scene's shape names (``"shape <i>"``
    where unnamed, the index added where two agree), else the coatings' names
    (``"material <i>"`` where unnamed or two agree)."""
    if isinstance(geometry, Scene) and not geometry.is_mesh:
        names = [s.name if s.name is not None else f"shape {i}"
                 for i, s in enumerate(geometry.shapes)]
        if len(set(names)) != len(names):
            names = [f"{nm} ({i})" for i, nm in enumerate(names)]
        return tuple(names), tuple(s.material for s in geometry.shapes)
    materials = tuple(geometry.materials)
    names = tuple(getattr(m, "name", None) or f"material {i}"
                  for i, m in enumerate(materials))
    if len(set(names)) != len(names):
        names = tuple(f"material {i}" for i in range(len(names)))
    return names, materials


def scene_aliases(scene, names):
    """A mesh scene's part names → the index of the coating the parts of that name hold
    alone (its kernel part, named ``names[i]``), or a str saying why they hold none alone
    (several coatings, or one that a part of another name holds too); a part named as a
    coating is left out (the coating's name wins). Empty for anything but a mesh Scene."""
    if not isinstance(scene, Scene) or not scene.is_mesh:
        return {}
    held = {}
    for part in scene.parts:
        if part.name not in names:
            held.setdefault(part.name, set()).update(
                np.unique(np.asarray(part.material, dtype=np.int64)).tolist())
    return {name: _alias(name, mine, scene, names) for name, mine in held.items()}


def _alias(name, mine, scene, names):
    """:func:`scene_aliases`' entry for the parts named ``name``, holding coatings
    ``mine``."""
    if len(mine) != 1:
        return (f"part {name!r} holds {len(mine)} coatings {[names[i] for i in sorted(mine)]}"
                ": name them (a mesh's fit has a part per coating)")
    (mat,) = mine
    others = sorted({q.name for q in scene.parts if q.name != name
                     and mat in np.asarray(q.material, dtype=np.int64)})
    if not others:
        return int(mat)
    return (f"part {name!r} shares its coating {names[mat]!r} with {others} (a mesh's fit "
            f"has a part per coating): give {name!r} a coating of its own "
            f"(Scene.from_mesh(..., materials={{{name!r}: ...}})) to fit it alone, or name "
            f"{names[mat]!r} to fit them together")


def analytic_fields(scene, ladar, radiometry, samples):
    """The kernel of an analytic scene with ``samples`` pieces per boundary."""
    n_views, n_bins = ladar.n_views, ladar.bin_edges.size - 1
    mats = [interp_matrix(r, t, w, n_views * n_bins, GRID, cubic=True) for r, t, w in
            analytic_triplets(scene, ladar, radiometry == "power", samples)]
    names, materials = parts_of(scene)
    return dict(matrices=tuple(mats), parts=names, materials=materials,
                shape=(n_views, n_bins), angles_deg=ladar.angles_deg,
                bin_edges=ladar.bin_edges, view_vectors=ladar.view_vectors,
                radiometry=radiometry, source="analytic",
                info={"samples_per_shape": samples, "units": "length/sr"},
                _traced=(scene, ladar))


def hits_fields(hits, radiometry):
    """The kernel of a trace's monostatic hits, a part per material index."""
    if hits.bistatic is not None:
        raise ParameterError("coating kernels are monostatic; these hits are bistatic")
    edges = hits.ladar.bin_edges
    n_views, n_bins = hits.ladar.n_views, edges.size - 1
    k = np.searchsorted(edges, hits.range, side="right") - 1
    ok = (hits.cos_theta >= 0) & (k >= 0) & (k < n_bins)
    # weigh's F·δA⊥ (paper) or F cos θ·δA⊥ (power) as ω × the table's F cos θ
    omega = per_table_weight(hits, radiometry == "power")
    theta = np.arctan2(hits.sin_theta, np.maximum(hits.cos_theta, 0.0))
    rows = hits.view.astype(np.int64) * n_bins + k
    mats = []
    for m in range(len(hits.materials)):
        sel = ok & (hits.material == m)
        mats.append(interp_matrix(rows[sel], theta[sel], omega[sel], n_views * n_bins, GRID))
    names, materials = parts_of(hits)
    return dict(matrices=tuple(mats), parts=names, materials=materials,
                shape=(n_views, n_bins), angles_deg=hits.ladar.angles_deg, bin_edges=edges,
                view_vectors=hits.ladar.view_vectors, radiometry=radiometry, source="mesh",
                info={"mode": hits.mode, "normals": hits.normals,
                      "rays": int(np.sum(hits.rays))})


def traced_mesh_fields(scene, ladar, radiometry, rays_per_bin, options):
    """The kernel of a mesh scene traced with ``rays_per_bin`` (None: trace's default) and
    the trace ``options``."""
    hits = trace(scene, ladar, rays_per_bin=rays_per_bin, **options)
    fields = hits_fields(hits, radiometry)
    spacing = float(hits.info["ray_spacing"])
    return {**fields, "_traced": (scene, ladar, options),
            "info": {**fields["info"], "ray_spacing": spacing,
                     "rays_per_bin": float(np.min(np.diff(ladar.bin_edges))) / spacing}}
