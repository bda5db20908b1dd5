"""The command line's source loader: a scene from what a user names on the command line (a
packaged phantom, a phantom spec or any mesh file)."""

from __future__ import annotations

import os
import re

from .. import materials as _materials
from .. import phantoms
from ..errors import MeshladarError, ParameterError
from ..scene import Scene

__all__ = ["load_source"]

#: The scene loaders' refusal of a coating for a part or shape the scene lacks (the
#: loaders call the overrides ``materials``; a phantom's message begins with its file).
_UNKNOWN_PART = re.compile(r"(?:^|: )materials: (no (?:part|shape) named .*)$", re.DOTALL)


def _labelled(exc, source, lab):
    """A loader's refusal in the caller's words: an unknown part's under the coatings'
    label; one that does not name ``source`` (a degenerate mesh's) prefixed with it."""
    text = str(exc)
    unknown = _UNKNOWN_PART.search(text)
    if unknown:
        return type(exc)(f"{lab['coatings']}: {unknown.group(1)}")
    if source not in text:
        return type(exc)(f"{lab['source']} {source!r}: {text}")
    return exc


def load_source(source, *, material=None, coatings=None, materials_file=None, labels=None):
    """A scene from what a user names: a packaged phantom, a phantom spec or a mesh file.

    Dispatch is on what ``source`` is, not on a list of suffixes: a packaged phantom's name
    or a ``.toml`` spec is a phantom; any other path goes to trimesh, which reads the format
    from the file (archives, GLB/GLTF, 3MF, DAE... when their optional readers are
    installed).

    Parameters
    ----------
    source : str
        A phantom's name (:func:`meshladar.phantoms.names`), a phantom spec (``.toml``) or a mesh file.
    material : str, optional
        A mesh's coating, by name (default "dark_gray"); a phantom's shapes have their own.
    coatings : dict, optional
        ``{part or shape name: coating name}`` overrides.
    materials_file : path, optional
        A TOML material table whose coatings join (and override by name) the packaged ones.
    labels : dict, optional
        What the caller calls ``source``, ``material`` and ``coatings`` in its errors (the
        command line passes its flags).

    Returns
    -------
    (Scene, Ladar or None, str)
        The scene, the phantom's own ladar set-up (None for a mesh), and the model it is
        simulated with by default ("analytic" for a phantom, "mesh" for a mesh).

    Raises
    ------
    MeshladarError
        The loaders' refusals (a ParameterError, GeometryError or PhantomSpecError): an
        unknown coating or part under the labels of ``material`` and ``coatings``; a mesh
        file's own (no faces left, say) naming ``source`` and the file.
    """

    lab = {"source": "source", "material": "material", "coatings": "coatings",
           **(labels or {})}
    table = dict(phantoms.materials())
    if materials_file is not None:
        table.update(_materials.load_table(materials_file))

    def coating(name, label):
        if name not in table:
            raise ParameterError(f"{label}: unknown coating {name!r}; known: {sorted(table)}")
        return table[name]

    if not phantoms.is_phantom(source):
        if not os.path.exists(source):
            raise ParameterError(f"{lab['source']}: no such mesh file {source!r}, and not a "
                                 f"known phantom ({', '.join(phantoms.names())})")
        base = coating("dark_gray" if material is None else material, lab["material"])
        per_part = {k: coating(v, lab["coatings"]) for k, v in (coatings or {}).items()}
        try:
            return Scene.from_mesh(source, base, materials=per_part or None), None, "mesh"
        except MeshladarError as exc:
            raise _labelled(exc, source, lab) from None
    if material is not None:
        raise ParameterError(f"{lab['material']} colours a mesh's parts; a phantom's shapes "
                             f"have their own coatings: use {lab['coatings']} SHAPE=NAME")
    overrides = {k: coating(v, lab["coatings"]) for k, v in (coatings or {}).items()}
    try:
        ph = phantoms.load(source, materials=overrides or None)
    except MeshladarError as exc:
        raise _labelled(exc, source, lab) from None
    return ph.scene, ph.ladar, "analytic"
