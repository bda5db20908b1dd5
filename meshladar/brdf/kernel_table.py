"""The material table of the compiled SR kernel, in plain numpy: one coating's row
(:class:`KernelRow`, a coating's ``kernel_params``) and the stacked table the engine's
compiled loops read (:func:`material_table`).

The compiled kernel itself, ``meshladar.brdf._sandford_robertson_kernel.sr_monostatic``,
imports numba; this module does not, so the models that give a row
(:class:`~meshladar.brdf.SandfordRobertson`, :class:`~meshladar.brdf.Lambertian`) stay
light. The names are also importable from :mod:`meshladar.brdf`, ``KernelRow`` from
:mod:`meshladar.brdf.sandford_robertson` and ``material_table`` from
:mod:`meshladar.brdf.base`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._validate import short
from ..errors import ParameterError

__all__ = ["KernelRow", "material_table"]


class KernelRow(NamedTuple):
    """One coating's row of the compiled SR kernel's material table (the flat arguments of
    the compiled ``sr_monostatic`` after cos θ, sin²θ).

    Attributes
    ----------
    rho_d : float
        Diffuse spectral reflectivity ρd (A1).
    epsilon : float
        Spectral emissivity ε (A7).
    b : float
        Grazing-angle reflectivity (A2).
    e : float
        Glint eccentricity (A6).
    G : float
        Diffuse normalisation G(b) (A3).
    has_diffuse : float
        1.0 when the diffuse lobe is summed, else 0.0.
    has_specular : float
        1.0 when the specular (glint) lobe is summed, else 0.0.
    """

    rho_d: float
    epsilon: float
    b: float
    e: float
    G: float
    has_diffuse: float
    has_specular: float


def material_table(materials):
    """(n, 7) float64 rows of (rho_d, epsilon, b, e, G, has_diffuse, has_specular): each
    material's ``kernel_params``, the table the engine's compiled loops read (every material
    must have them for the compiled path).

    Parameters
    ----------
    materials : sequence of BRDF
        The n coatings, in material-index order (n ≥ 0). Each must have ``kernel_params``
        that are not None: of the built-in models, :class:`meshladar.brdf.SandfordRobertson`
        and :class:`meshladar.brdf.Lambertian`; a user's row must be 7 finite numbers.

    Returns
    -------
    (n, 7) ndarray of float64
        Row i is ``materials[i].kernel_params`` (a
        :class:`meshladar.brdf.KernelRow`); (0, 7) for no materials.

    Raises
    ------
    ParameterError
        When ``materials`` is not a sequence, or a material has no ``kernel_params`` (the
        models without a compiled kernel are weighed through ``value`` instead) or a row
        that is not 7 finite numbers; the message names the material's index and type.
    """
    if not isinstance(materials, (list, tuple)):
        raise ParameterError(f"materials must be a list or tuple of BRDFs; got "
                             f"{short(materials)}")
    rows = [_row(i, m) for i, m in enumerate(materials)]
    return np.array(rows, dtype=np.float64).reshape(len(rows), len(KernelRow._fields))


def _row(i, material):
    """``material.kernel_params`` as 7 finite floats, or a ParameterError naming it."""
    params = getattr(material, "kernel_params", None)
    kind = type(material).__name__
    if params is None:
        raise ParameterError(f"materials[{i}]: {kind} has no kernel_params (a row of the "
                             f"compiled SR kernel); material_table takes coatings that have "
                             f"one (SandfordRobertson, Lambertian), others are weighed "
                             f"through their value()")
    try:
        row = np.asarray(params, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"materials[{i}]: {kind}.kernel_params must be 7 real numbers "
                             f"{KernelRow._fields}; got {short(params)}") from exc
    if row.shape != (len(KernelRow._fields),) or not np.all(np.isfinite(row)):
        raise ParameterError(f"materials[{i}]: {kind}.kernel_params must be 7 finite numbers "
                             f"{KernelRow._fields}; got {short(params)}")
    return row
