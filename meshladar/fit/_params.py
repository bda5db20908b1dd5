"""The parameters a coating fit frees: which fields of which part, their bounds, the
coatings with values put in, and the model's Jacobian through a part's kernel matrix."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..brdf import SandfordRobertson
from .._validate import check_real, short
from ..errors import ParameterError
from ._tables import GRID, _table

#: Default bounds of the Sandford-Robertson parameters.
SR_BOUNDS = {"rho_d": (0.0, 1.0), "epsilon": (0.0, 1.0), "b": (0.0, 1.0), "e": (1e-4, 1.0)}


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



def _resolve_params(kernel, parts, free, bounds, initial):
    mats = list(kernel.materials)
    if initial is not None:
        for key, m in dict(initial).items():
            mats[kernel.part_index(key)] = m
    chosen = range(len(kernel.parts)) if parts is None else [kernel.part_index(p)
                                                            for p in parts]
    chosen = sorted(set(chosen))
    params = []
    for p in chosen:
        m = mats[p]
        names = _float_fields(m)
        if free is not None:
            want = free.get(kernel.parts[p], free.get(p)) if isinstance(free, dict) else free
            if want is None:
                continue
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
        for n in names:
            lo, hi = SR_BOUNDS.get(n, (-math.inf, math.inf)) if isinstance(
                m, SandfordRobertson) else (-math.inf, math.inf)
            valid = (lo, hi)
            if bounds is not None:
                for key in (f"{kernel.parts[p]}.{n}", f"{p}.{n}", n):
                    if key in bounds:
                        lo, hi = _bound_pair(key, bounds[key])
                        break
            if lo < valid[0] or hi > valid[1]:
                raise ParameterError(f"bounds of {kernel.parts[p]}.{n} must lie in its valid "
                                     f"range [{valid[0]:g}, {valid[1]:g}]; got ({lo:g}, {hi:g})")
            if not lo < hi:
                raise ParameterError(f"bounds of {kernel.parts[p]}.{n} must be (low, high) "
                                     f"with low < high; got ({lo}, {hi})")
            params.append(_Param(p, n, lo, hi))
    if not params:
        raise ParameterError("nothing to fit: no free parameters in the chosen parts")
    return mats, params


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
    """∂(model)/∂(parameters), (n_rows, n): each parameter's table derivative by a one-sided
    step into its bounds, through its part's matrix ``K[part]``."""
    J = np.zeros((n_rows, len(params)))
    if base is None:
        return J
    for p in sorted({q.part for q in params}):
        cols = [i for i, prm in enumerate(params) if prm.part == p]
        D = np.zeros((GRID, len(cols)))
        for c, i in enumerate(cols):
            prm = params[i]
            h = 1e-7 * max(1.0, abs(x[i])) if prm.name != "e" else 1e-5 * max(x[i], 1e-4)
            step = h if x[i] + h <= prm.high else -h
            moved = np.array(x, dtype=float)
            moved[i] = x[i] + step
            try:
                D[:, c] = (_table(_materials(mats, params, moved)[p]) - base[p]) / step
            except ParameterError:
                continue
        J[:, cols] = (K[p] @ D) * scale
    return J
