"""The parameters a coating fit frees: which fields of which part, their bounds, the
coatings with values put in, and the model's Jacobian through a part's kernel matrix.

A built-in coating's parameters are bounded by their valid ranges (:data:`VALID_RANGES`, as
the classes check them, but SR's e from 1e-4 and Phong's exponent below only): the solver
never steps out of them, a parameter on its bound is handled as SR's, and the Jacobian's
finite-difference step goes the other way where a step would leave the coating's valid set
(Phong's kd + ks ≤ 1, SR's ρd + ε ≤ G(b)). Unknown names in ``free`` and ``bounds`` are
refused."""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..brdf import GGX, Lambertian, Phong, SandfordRobertson
from .._validate import check_real, short
from ..errors import EnergyConservationWarning, ParameterError
from ._tables import GRID, _table

#: Default bounds of the Sandford-Robertson parameters: the class's valid ranges, but e from
#: 1e-4 (the class takes e down to E_MIN).
SR_BOUNDS = {"rho_d": (0.0, 1.0), "epsilon": (0.0, 1.0), "b": (0.0, 1.0), "e": (1e-4, 1.0)}

#: The built-in coatings' float fields with their valid ranges, as each class checks them
#: when it is made but SR's e from 1e-4 (:data:`SR_BOUNDS`): a fit's default bounds, and the
#: widest it takes. Phong's exponent is bounded below only: its class's cap, 1e6 (a lobe
#: of 1.4 mrad), would stand for its scale where parameters are weighed by their ranges
#: (design_views: for an exponent of 30, the σ of 8 even views came out 42 % low), and a
#: step past it is an invalid point to the solver. Other fields (a user's own BRDF) are
#: unbounded unless bounds= says.
VALID_RANGES = ((SandfordRobertson, SR_BOUNDS),
                (Lambertian, {"albedo": (0.0, 1.0)}),
                (Phong, {"kd": (0.0, 1.0), "ks": (0.0, 1.0), "exponent": (0.0, math.inf)}),
                (GGX, {"alpha": (1e-4, 1.0), "reflectance": (0.0, 1.0)}))


def valid_range(material, name):
    """(low, high) of field ``name`` of ``material``: its class's valid range where
    :data:`VALID_RANGES` has it, else (-inf, inf)."""
    for cls, ranges in VALID_RANGES:
        if isinstance(material, cls):
            return ranges.get(name, (-math.inf, math.inf))
    return (-math.inf, math.inf)


def _float_fields(material):
    if not dataclasses.is_dataclass(material):
        return ()
    return tuple(f.name for f in dataclasses.fields(material)
                 if f.init and f.name != "name" and isinstance(getattr(material, f.name),
                                                                 (float, int))
                 and not isinstance(getattr(material, f.name), bool))


@dataclass(frozen=True)
class _Param:
    part: int
    name: str
    low: float
    high: float

    @property
    def label(self):
        return f"{self.part}.{self.name}"


def part_index(parts, part) -> int:
    """The index of ``part`` (a name in ``parts``, or an index in [0, len(parts)); bools
    refused) into ``parts``; a ParameterError naming the parts otherwise."""
    if isinstance(part, (int, np.integer)) and not isinstance(part, bool):
        if 0 <= part < len(parts):
            return int(part)
    elif part in parts:
        return parts.index(part)
    raise ParameterError(f"part must be one of {list(parts)} or an index below "
                         f"{len(parts)}; got {part!r}")


class PartList(NamedTuple):
    """A geometry's part names and coatings, as a kernel would have them (what
    :func:`_resolve_params` reads before a kernel is traced), and ``aliases``: a mesh
    scene's own part names → the index of the coating each holds alone, or why it holds
    none alone (a str: :func:`meshladar.fit._building.scene_aliases`)."""

    parts: tuple
    materials: tuple
    aliases: dict = {}

    def part_index(self, part):
        """The index of a part's name or index (:func:`part_index`), or of the coating a
        mesh scene's part of that name holds alone."""
        _refused_alias(self, part)
        if isinstance(part, str) and part not in self.parts and part in self.aliases:
            return self.aliases[part]
        try:
            return part_index(self.parts, part)
        except ParameterError:
            if not self.aliases:
                raise
            raise ParameterError(f"part must be one of {list(self.parts)} (a mesh's fit has "
                                 f"a part per coating, named by it), an index below "
                                 f"{len(self.parts)} or one of the scene's parts "
                                 f"{list(self.aliases)}; got {part!r}") from None


def names_of(kernel, p):
    """The names part ``p`` of ``kernel`` answers to in ``free`` and ``bounds``: its own,
    and the scene's parts that hold its coating alone (:class:`PartList`'s aliases)."""
    aliases = getattr(kernel, "aliases", {})
    return (kernel.parts[p],) + tuple(a for a, i in aliases.items() if i == p)


def _resolve_params(kernel, parts, free, bounds, initial):
    """(each part's coating, the free :class:`_Param` list) of ``kernel`` (anything with
    ``parts``, ``materials`` and ``part_index``), every argument checked first."""
    mats = list(kernel.materials)
    if initial is not None:
        for key, m in dict(initial).items():
            mats[kernel.part_index(key)] = m
    chosen = range(len(kernel.parts)) if parts is None else [kernel.part_index(p)
                                                            for p in parts]
    chosen = sorted(set(chosen))
    if isinstance(free, dict):
        _check_free_parts(kernel, chosen, free)
    if bounds is not None and not isinstance(bounds, Mapping):
        raise ParameterError(f"bounds must be a dict of 'part.param', 'index.param' or "
                             f"'param' → (low, high); got {short(bounds)}")
    params = []
    for p in chosen:
        for n in _free_names(kernel, p, mats[p], free):
            params.append(_Param(p, n, *_bounds_of(kernel, p, mats[p], n, bounds)))
    if not params:
        raise ParameterError("nothing to fit: no free parameters in the chosen parts")
    _check_bound_keys(kernel, params, bounds)
    return mats, params


def _check_free_parts(kernel, chosen, free):
    """A dict ``free``'s keys: each a part (name or index) that is fitted, once."""
    bad, seen = [], {}
    for key in free:
        _refused_alias(kernel, key)
        try:
            index = kernel.part_index(key)
        except ParameterError:
            bad.append(key)
            continue
        if index not in chosen:
            raise ParameterError(f"free names part {kernel.parts[index]!r}, which parts= "
                                 f"leaves out (fitted: {[kernel.parts[i] for i in chosen]})")
        if index in seen:
            raise ParameterError(f"free names part {kernel.parts[index]!r} twice (as "
                                 f"{seen[index]!r} and {key!r}): give it once")
        seen[index] = key
    if bad:
        scene = (f" or the scene's parts {list(kernel.aliases)}"
                 if getattr(kernel, "aliases", None) else "")
        raise ParameterError(f"free's parts must be among {list(kernel.parts)} (or an "
                             f"index below {len(kernel.parts)}){scene}; got {bad}")


def _refused_alias(kernel, key):
    """Raise why a scene part named ``key`` names no coating alone (:class:`PartList`)."""
    found = getattr(kernel, "aliases", {}).get(key) if isinstance(key, str) else None
    if isinstance(found, str) and key not in kernel.parts:
        raise ParameterError(found)


def _free_names(kernel, p, m, free):
    """The names of part ``p``'s free parameters (its coating ``m``), checked."""
    names = _float_fields(m)
    if free is not None:
        want = (next((free[k] for k in (*names_of(kernel, p), p) if k in free), None)
                if isinstance(free, dict) else free)
        if want is None:
            return ()
        want = (want,) if isinstance(want, str) else tuple(want)
        bad = [n for n in want if n not in names]
        if bad:
            raise ParameterError(f"free parameters of part {kernel.parts[p]!r} must be "
                                 f"among {list(names)}; got {bad}")
        names = want
    elif isinstance(m, SandfordRobertson):
        names = tuple(n for n in ("rho_d", "epsilon", "b", "e")
                      if not (m.lobes == "diffuse" and n in ("epsilon", "e")))
    if not names:
        raise ParameterError(f"part {kernel.parts[p]!r}: {type(m).__name__} has no float "
                             "dataclass fields to fit; give free=")
    return names


def _bounds_of(kernel, p, m, n, bounds):
    """(low, high) of part ``p``'s parameter ``n``: ``bounds``' where given (within the
    valid range), else the valid range."""
    lo, hi = valid = valid_range(m, n)
    if bounds is not None:
        for key in (*(f"{a}.{n}" for a in names_of(kernel, p)), f"{p}.{n}", n):
            if key in bounds:
                lo, hi = _bound_pair(key, bounds[key])
                break
    if lo < valid[0] or hi > valid[1]:
        raise ParameterError(f"bounds of {kernel.parts[p]}.{n} must lie in its valid "
                             f"range [{valid[0]:g}, {valid[1]:g}]; got ({lo:g}, {hi:g})")
    if not lo < hi:
        raise ParameterError(f"bounds of {kernel.parts[p]}.{n} must be (low, high) "
                             f"with low < high; got ({lo}, {hi})")
    return lo, hi


def _check_bound_keys(kernel, params, bounds):
    """Every key of ``bounds`` names a free parameter: 'part.param', 'index.param' or a
    bare 'param' that some fitted part frees."""
    if not bounds:
        return
    labels = [f"{kernel.parts[q.part]}.{q.name}" for q in params]
    bare = list(dict.fromkeys(q.name for q in params))
    known = set(bare) | {q.label for q in params} | {
        f"{a}.{q.name}" for q in params for a in names_of(kernel, q.part)}
    bad = [key for key in bounds if key not in known]
    for key in bad:
        _refused_alias(kernel, str(key).rpartition(".")[0])
    if bad:
        raise ParameterError(f"bounds' keys must name free parameters, among "
                             f"{labels + bare} (or 'index.param', e.g. {params[0].label!r}); "
                             f"got {bad}")


def _bound_pair(key, pair):
    """``bounds[key]`` as two floats (checked: a pair of real numbers, ±inf allowed)."""
    if not isinstance(pair, (tuple, list, np.ndarray)) or len(pair) != 2:
        raise ParameterError(f"bounds[{key!r}] must be a (low, high) pair; got {short(pair)}")
    return tuple(v if isinstance(v, float) and math.isinf(v)
                 else check_real(f"bounds[{key!r}]", v) for v in pair)


def _materials(mats, params, x):
    out = list(mats)
    by_part = {}
    for prm, v in zip(params, x):
        by_part.setdefault(prm.part, {})[prm.name] = float(v)
    for p, kw in by_part.items():
        out[p] = dataclasses.replace(out[p], **kw)
    return out


def _jacobian(K, mats, params, x, base, scale, n_rows):
    """∂(model)/∂(parameters), (n_rows, n): each parameter's table derivative
    (:func:`_table_derivative`) through its part's matrix ``K[part]``."""
    J = np.zeros((n_rows, len(params)))
    if base is None:
        return J
    for p in sorted({q.part for q in params}):
        cols = [i for i, prm in enumerate(params) if prm.part == p]
        D = np.zeros((GRID, len(cols)))
        for c, i in enumerate(cols):
            D[:, c] = _table_derivative(mats, params, x, i, base[p])
        J[:, cols] = (K[p] @ D) * scale
    return J


def _table_derivative(mats, params, x, i, base):
    """Parameter i's table derivative by a one-sided step: into its bounds, or the other
    way where that step leaves the coating's valid set (kd + ks = 1 of a Phong coating
    allows a step down only); zeros only where neither step makes a valid coating."""
    prm = params[i]
    h = 1e-7 * max(1.0, abs(x[i])) if prm.name != "e" else 1e-5 * max(x[i], 1e-4)
    first = h if x[i] + h <= prm.high else -h
    for step in (first, -first):
        moved = np.array(x, dtype=float)
        moved[i] = x[i] + step
        try:
            with warnings.catch_warnings():
                # a step may leave energy conservation, as the solver's trial points may
                warnings.simplefilter("ignore", EnergyConservationWarning)
                table = _table(_materials(mats, params, moved)[prm.part])
        except ParameterError:
            continue
        return (table - base) / step
    return np.zeros(GRID)
