"""Scenes and sensors the scan tests share: planes and plates built with trimesh, far from
the sensor, and a sensor whose link budget is easy to write by hand."""

from __future__ import annotations

import numpy as np
import trimesh

import meshladar as ml
from meshladar.scan import ScanBeam, ScanSensor

SPEED_OF_LIGHT = 299_792_458.0
PLANCK = 6.626_070_15e-34
#: Lambertian albedo of every test surface.
ALBEDO = 0.5


def plate(distance, half=20.0, thickness=0.01, hole=None):
    """A square plate facing −x, its front face at x = ``distance``; with ``hole`` (a
    radius) a circular hole about the x axis (a thin cylinder subtracted, or a ring of
    triangles where boolean engines are absent)."""
    if hole is None:
        box = trimesh.creation.box((thickness, 2 * half, 2 * half))
        box.apply_translation((distance + thickness / 2, 0.0, 0.0))
        return box
    return annulus(distance, hole, half)


def annulus(distance, inner, outer, segments=256):
    """A flat ring facing −x at x = ``distance``: inner radius ``inner``, outer ``outer``
    (a square's half side is not needed: the ring is wide enough to hold the beam)."""
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    ring = lambda r: np.stack([np.full_like(a, distance), r * np.cos(a), r * np.sin(a)], 1)
    v = np.concatenate([ring(inner), ring(outer)])
    i = np.arange(segments)
    j = (i + 1) % segments
    f = np.concatenate([np.stack([i, j, segments + i], 1),
                        np.stack([j, segments + j, segments + i], 1)])
    return trimesh.Trimesh(v, f, process=False)


def scene(*meshes):
    """A scene of the meshes, one part each (in order), all Lambertian of :data:`ALBEDO`."""
    coating = ml.brdf.Lambertian(ALBEDO)
    return ml.Scene.from_meshes([(m, coating) for m in meshes])


def sensor(**kw):
    kw.setdefault("pulse_energy", 1e-6)
    kw.setdefault("aperture_diameter", 0.05)
    kw.setdefault("sample_rate", 2e9)
    kw.setdefault("beam", ScanBeam(0.0))
    return ScanSensor(**kw)


def photoelectrons_by_hand(energy, aperture, distance, cos_theta=1.0, share=1.0,
                           wavelength=1.064e-6):
    """E s (ρ/π) cos θ (π D²/4)/R² / (h c/λ): a Lambertian surface's echo, by hand."""
    photons = energy * share / (PLANCK * SPEED_OF_LIGHT / wavelength)
    return photons * ALBEDO / np.pi * cos_theta * np.pi * aperture ** 2 / 4 / distance ** 2
