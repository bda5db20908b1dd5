"""The phantom library: the paper's phantoms and coatings as small declarative specs.

Installed as ``meshladar.phantoms``. Each phantom is a TOML file in this folder (``disk``,
``ellipse``, ``disk_pair``) holding its shapes, a coating per shape and the paper's ladar
set-up; :func:`load` builds it. Coatings are named from the engine's table
(:data:`meshladar.materials.PAPER`, read from ``meshladar/materials.toml``), or given
inline as a table of SR parameters, and can be overridden per shape::

    from meshladar import phantoms
    pair = phantoms.load("disk_pair", materials={"large": "dark_gray", "small": "aluminum"})
    sino = ml.simulate(pair.scene, pair.ladar)

Spec format (all lengths in scene units)::

    name = "disk_pair"
    description = "..."
    [ladar]
    bin_width = 0.003125                      # or bin_edges = [...]
    n_bins = 512                              # centred on range 0
    angles_deg = { start = 0.0, stop = 360.0, step = 1.0 }   # or a list
    [[shape]]
    name = "large"
    kind = "disk"                             # or "ellipse" with semi_axes, angle_deg
    center = [-0.3, 0.0]
    radius = 0.4
    material = "dark_gray"                    # a name, or { rho_d = ..., epsilon = ..., ... }
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib import resources

import numpy as np

import meshladar as ml
from meshladar import materials as _materials
from meshladar._validate import check_path
from meshladar.brdf import BRDF
from meshladar.errors import MeshladarError, ParameterError, PhantomSpecError
from meshladar.ladar import MAX_VIEWS
from meshladar.materials import parse_table, read_toml
from meshladar.scene import Scene

__all__ = ["Phantom", "load", "scene", "names", "materials", "is_phantom",
           "MATERIALS_TOML"]

#: Path of the packaged coating table (the engine's, :data:`meshladar.materials.TABLE_PATH`).
MATERIALS_TOML = _materials.TABLE_PATH

_SHAPE_FIELDS = {"disk": ("name", "kind", "center", "radius", "material"),
                 "ellipse": ("name", "kind", "center", "semi_axes", "angle_deg", "material")}
_LADAR_FIELDS = ("bin_width", "n_bins", "bin_edges", "angles_deg")
_SPEC_KEYS = ("name", "description", "ladar", "shape")
#: Views a spec may ask for (the engine's limit).
_MAX_VIEWS = MAX_VIEWS


def materials():
    """The packaged coating table as a read-only mapping of name to SandfordRobertson
    (:data:`meshladar.materials.PAPER`).

    Returns
    -------
    Mapping of str to SandfordRobertson
        The table read from :data:`MATERIALS_TOML` (the same object on every call).
    """
    return _materials.PAPER


def names() -> list[str]:
    """Names of the packaged phantoms.

    Returns
    -------
    list of str
        The ``.toml`` specs packaged in this folder, without the suffix, sorted
        (``["disk", "disk_pair", "ellipse"]`` as shipped).
    """
    return sorted(p.name[:-5] for p in resources.files(__name__).iterdir()
                  if p.name.endswith(".toml"))


@dataclass(frozen=True)
class Phantom:
    """A built phantom: its scene and the paper's ladar set-up for it.

    Attributes
    ----------
    name : str
        The spec's ``name`` (default "phantom").
    description : str
        The spec's ``description`` (default empty).
    scene : Scene
        Its shapes, each with its coating.
    ladar : Ladar
        The spec's ``[ladar]``: its views (default 0°, 1°, ..., 359°) and bins (default 512
        of width 0.003125 centred on range 0, or its ``bin_edges``).
    """

    name: str
    description: str
    scene: object
    ladar: object


def _error(source, msg):

    return PhantomSpecError(f"{source}: {msg}")


def _resolve_material(value, table, where, source):

    if isinstance(value, BRDF):
        return value
    if isinstance(value, str):
        if value not in table:
            raise _error(source, f"{where}: unknown material {value!r}; known: {sorted(table)}")
        return table[value]
    if isinstance(value, dict):
        try:
            return parse_table({where: value}, source=source)[where]
        except ValueError as exc:
            raise _error(source, str(exc).split(": ", 1)[-1]) from exc
    raise _error(source, f"{where}: material must be a name, an inline table or a "
                         f"meshladar.brdf.BRDF; got {value!r}")


def _angles(spec, source):
    if isinstance(spec, dict):
        unknown = set(spec) - {"start", "stop", "step"}
        if unknown or not {"start", "stop", "step"} <= set(spec):
            raise _error(source, "[ladar] angles_deg must be a list or {start, stop, step}; "
                                 f"got {spec!r}")
        from numbers import Real

        bad = [k for k in ("start", "stop", "step") if isinstance(spec[k], bool)
               or not isinstance(spec[k], Real)]
        if bad:
            raise _error(source, f"[ladar] angles_deg {bad[0]} must be a number; got "
                                 f"{spec[bad[0]]!r}")
        if not spec["step"] > 0:
            raise _error(source, f"[ladar] angles_deg step must be > 0; got {spec['step']!r}")
        count = (spec["stop"] - spec["start"]) / spec["step"]
        if not count <= _MAX_VIEWS:
            raise _error(source, f"[ladar] angles_deg {spec!r} would make {count:.3g} views; "
                                 f"at most {_MAX_VIEWS:.0e} (a larger step)")
        return np.arange(spec["start"], spec["stop"], spec["step"], dtype=np.float64)
    return spec


def _build(spec, source, overrides):

    table = dict(materials())
    extra = sorted(set(spec) - set(_SPEC_KEYS))
    if extra:
        raise _error(source, f"unknown key {extra[0]!r}; valid keys are {_SPEC_KEYS}")
    if not isinstance(spec.get("ladar", {}), dict):
        raise _error(source, f"[ladar] must be a table; got {spec['ladar']!r}")
    shapes_spec = spec.get("shape")
    if not isinstance(shapes_spec, list) or not shapes_spec:
        raise _error(source, "expected at least one [[shape]] table")
    overrides = dict(overrides or {})
    known_names = [s.get("name") for s in shapes_spec if isinstance(s, dict)]
    unknown = sorted(set(overrides) - set(known_names))
    if unknown:
        raise _error(source, f"materials: no shape named {unknown[0]!r}; shapes are "
                             f"{known_names}")
    shapes = []
    for i, s in enumerate(shapes_spec):
        where = f"[[shape]] {i} ({s.get('name', 'unnamed') if isinstance(s, dict) else s!r})"
        if not isinstance(s, dict):
            raise _error(source, f"{where} must be a table")
        kind = s.get("kind")
        if kind not in _SHAPE_FIELDS:
            raise _error(source, f"{where}: kind must be one of {tuple(_SHAPE_FIELDS)}; "
                                 f"got {kind!r}")
        extra = sorted(set(s) - set(_SHAPE_FIELDS[kind]))
        if extra:
            raise _error(source, f"{where}: unknown field {extra[0]!r} for a {kind}; valid "
                                 f"fields are {_SHAPE_FIELDS[kind]}")
        missing = [f for f in _SHAPE_FIELDS[kind] if f not in s and f not in ("name",)]
        if missing and not (missing == ["material"] and s.get("name") in overrides):
            raise _error(source, f"{where}: missing field {missing[0]!r}")
        mat = _resolve_material(overrides.get(s.get("name"), s.get("material")), table, where,
                                source)
        try:
            if kind == "disk":
                shapes.append(ml.Disk(s["center"], s["radius"], mat, name=s.get("name")))
            else:
                shapes.append(ml.Ellipse(s["center"], s["semi_axes"], s.get("angle_deg", 0.0),
                                         mat, name=s.get("name")))
        except MeshladarError as exc:
            raise _error(source, f"{where}: {exc}") from exc
    try:
        scene = ml.Scene(shapes)
    except MeshladarError as exc:
        raise _error(source, str(exc)) from exc
    lad = spec.get("ladar", {})
    extra = sorted(set(lad) - set(_LADAR_FIELDS))
    if extra:
        raise _error(source, f"[ladar]: unknown field {extra[0]!r}; valid fields are "
                             f"{_LADAR_FIELDS}")
    angles = _angles(lad.get("angles_deg", {"start": 0.0, "stop": 360.0, "step": 1.0}), source)
    try:
        if "bin_edges" in lad:
            ladar = ml.Ladar(angles, lad["bin_edges"])
        else:
            ladar = ml.Ladar.centered(lad.get("n_bins", 512), lad.get("bin_width", 0.003125),
                                      angles_deg=angles)
    except MeshladarError as exc:
        raise _error(source, f"[ladar]: {exc}") from exc
    return Phantom(spec.get("name", "phantom"), spec.get("description", ""), scene, ladar)


def load(name_or_path, *, materials=None):
    """Build a phantom from its spec: a packaged name (see :func:`names`) or a TOML path.

    Parameters
    ----------
    name_or_path : str or os.PathLike
    materials : dict, optional
        Coating per shape name, overriding the spec: a material name from the packaged
        table, an inline dict of SR parameters, or a SandfordRobertson.

    Returns
    -------
    Phantom
        ``.scene`` and ``.ladar`` (the paper's set-up), ``.name``, ``.description``.
    """

    key = check_path("name_or_path", name_or_path)
    if materials is not None and not isinstance(materials, dict):

        raise ParameterError(f"materials must be a dict of shape name -> coating; got "
                             f"{type(materials).__name__}")
    if key in names():
        with resources.as_file(resources.files(__name__) / f"{key}.toml") as p:
            return load(p, materials=materials)
    if not key.endswith(".toml") and not os.path.exists(key):
        raise _error(key, f"unknown phantom; packaged phantoms are {names()}, or give a "
                          "path to a .toml spec")

    return _build(read_toml(key, "phantom spec", PhantomSpecError), key, materials)


def scene(name_or_path, coating=None, **coatings):
    """The phantom's scene with ``coating`` on every shape, or coatings by shape name
    (``scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)``); the spec's own where neither
    is given. The one source of the paper's phantoms for the engine, studies and tests.

    Parameters
    ----------
    name_or_path : str or os.PathLike
        A packaged phantom's name (:func:`names`) or a spec's path.
    coating : str, dict or BRDF, optional
        The coating of every shape not named in ``coatings``: a name from the packaged
        table, an inline dict of SR parameters, or a BRDF (default None: the spec's own).
    **coatings
        Coatings by shape name, as ``coating``.

    Returns
    -------
    Scene
        The phantom's scene.

    Raises
    ------
    ParameterError
        When a keyword names no shape of the phantom.
    PhantomSpecError
        When the phantom is unknown, its spec is not valid, or a coating is unknown (as
        :func:`load`).
    """
    base = load(name_or_path)
    shape_names = [s.name for s in base.scene.shapes]
    unknown = sorted(set(coatings) - set(shape_names))
    if unknown:

        raise ParameterError(f"no shape named {unknown[0]!r} in {base.name}; shapes are "
                             f"{shape_names}")
    chosen = {n: coatings.get(n, coating) for n in shape_names}
    chosen = {n: m for n, m in chosen.items() if m is not None}
    return load(name_or_path, materials=chosen).scene if chosen else base.scene



def is_phantom(source) -> bool:
    """Whether ``source`` names a phantom (a packaged phantom's name or a ``.toml`` spec)
    rather than a mesh file.

    Parameters
    ----------
    source : object
        What a user named: only a ``str`` can name a phantom.

    Returns
    -------
    bool
        True for a packaged phantom's name (:func:`names`) or a string ending in
        ``.toml`` (any case); the file is not opened.
    """
    return isinstance(source, str) and (source in names() or source.lower().endswith(".toml"))


def __getattr__(name):
    # resolve() became the command line's source loader (meshladar.cli.sources.load_source)
    if name == "resolve":
        import warnings

        from meshladar.cli import sources

        warnings.warn("meshladar.phantoms.resolve is deprecated: it is the command line's "
                      "source loader, meshladar.cli.sources.load_source", DeprecationWarning,
                      stacklevel=2)
        return sources.load_source
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
