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

__all__ = ["KernelRow", "material_table"]


class KernelRow(NamedTuple):
    """One coating's row of the compiled SR kernel's material table (the flat arguments of
    the compiled ``sr_monostatic`` after cos θ, sin θ).

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
        The n coatings, in material-index order. Each must have ``kernel_params`` that are
        not None (of the built-in models, :class:`meshladar.brdf.SandfordRobertson` and
        :class:`meshladar.brdf.Lambertian`); this is not checked here.

    Returns
    -------
    (n, 7) ndarray of float64
        Row i is ``materials[i].kernel_params`` (a
        :class:`meshladar.brdf.KernelRow`).
    """
    return np.array([m.kernel_params for m in materials], dtype=np.float64)
