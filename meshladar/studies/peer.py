"""A peer renderer for meshladar's received-power radiometry: Mitsuba 3 + mitransient.

:func:`mitransient_profile` renders the range profile of a Lambertian triangle mesh with
mitransient's transient path tracer (an orthographic sensor and a directional emitter,
collocated), in meshladar's units for ``radiometry="power"``: per range bin,
∫ F cos θ_i cos θ_r dA with F = ρ/π and unit irradiance on a plane normal to the beam.
:func:`available` says whether that renderer runs here, without risking the interpreter.

Two references need no peer at all: :func:`sphere_power_profile`, the closed form for a
Lambertian sphere, and :func:`convex_power_profile`, the exact bin integrals of a convex
(or otherwise unoccluded) faceted Lambertian mesh, with which :func:`bench_time_to_accuracy`
measures how much time each tool needs for a given accuracy. Both are defined in the
private ``_exact_profiles`` beside this module, and importable from here.

Mitsuba, mitransient and drjit are imported inside the functions that need them: importing
``meshladar`` (or this module) never loads them. Install (pinned, as measured)::

    apt-get install libllvm19          # Debian 12: drjit 1.5 aborts with its LLVM 15
    pip install mitsuba==3.9.1 mitransient==1.3.1 drjit==1.5.0

drjit looks for ``/usr/lib/{x86_64,aarch64}-linux-gnu/libLLVM*.so.*`` (with Debian's
libLLVM-15.so.1 and libLLVM.so.19.1 both there, it loads 19) unless the environment
variable ``DRJIT_LIBLLVM_PATH`` names the library file.
"""

from __future__ import annotations

import functools
import subprocess
import sys
import time
from typing import NamedTuple

import numpy as np

from ..forward import simulate
from ..ladar import Ladar
from ..materials import lambertian
from ..scene import Scene
from ._exact_profiles import convex_power_profile, sphere_power_profile
from ._mitsuba_scene import (_checked, _frame, _opl_mapping, _samples, _target,
                             _transient_scene)

__all__ = ["available", "mitransient_profile", "sphere_power_profile",
           "convex_power_profile", "bench_time_to_accuracy", "VARIANT", "PINS"]

#: mitransient's integrators exist only in the ``*_ad_*`` variants; the CPU one, one channel.
VARIANT = "llvm_ad_mono"

#: The versions this module was validated with (pip pins).
PINS = {"mitsuba": "3.9.1", "mitransient": "1.3.1", "drjit": "1.5.0"}

#: A tiny transient render: drjit compiles a kernel, which is where a wrong libLLVM aborts
#: the process (importing alone can succeed).
_PROBE = f"""
import mitsuba as mi
mi.set_variant({VARIANT!r})
import mitransient
import numpy as np
scene = mi.load_dict({{
    "type": "scene",
    "integrator": {{"type": "transient_path", "max_depth": 2}},
    "emitter": {{"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0}},
    "target": {{"type": "rectangle", "bsdf": {{"type": "diffuse"}}}},
    "sensor": {{"type": "orthographic",
               "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 3], target=[0, 0, 0],
                                                          up=[0, 1, 0]),
               "sampler": {{"type": "independent", "sample_count": 1}},
               "film": {{"type": "transient_hdr_film", "width": 4, "height": 4,
                        "temporal_bins": 4, "bin_width_opl": 1.0, "start_opl": 0.0,
                        "rfilter": {{"type": "box"}}}}}}
}})
steady, transient = mi.render(scene, spp=1)
assert np.isfinite(np.array(transient)).all()
print("ok")
"""


@functools.lru_cache(maxsize=None)
def _probe():
    """(works, message): the probe run in a child interpreter (drjit with an unsupported
    libLLVM aborts the process, which no ``try`` catches)."""
    try:
        res = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                             timeout=300)
    except (OSError, subprocess.SubprocessError) as exc:
        return False, f"the probe could not run: {exc}"
    if res.returncode == 0 and res.stdout.strip().endswith("ok"):
        return True, "ok"
    tail = (res.stderr or res.stdout)[-1500:]
    return False, (f"mitsuba + mitransient ({VARIANT}) do not run here (exit code "
                   f"{res.returncode}); install libllvm19 (Debian) and pip install "
                   f"mitsuba=={PINS['mitsuba']} mitransient=={PINS['mitransient']} "
                   f"drjit=={PINS['drjit']} (drjit finds libLLVM*.so.* in "
                   f"/usr/lib/<arch>-linux-gnu, or the file DRJIT_LIBLLVM_PATH names)\n{tail}")


def available(reason=False):
    """Whether Mitsuba 3 + mitransient import and render in the ``llvm_ad_mono`` variant.

    Probed once per process, in a subprocess, so a drjit abort (an unsupported libLLVM)
    cannot take this interpreter down. With ``reason=True`` returns (bool, message).

    The probe renders a 4 × 4 film of a diffuse rectangle with ``transient_path`` in a
    child interpreter (at most 300 s); its answer is cached for the process.

    Parameters
    ----------
    reason : bool
        Also return the probe's message (default False).

    Returns
    -------
    bool or (bool, str)
        Whether the renderer runs here; with ``reason``, also ``"ok"``, or why not: what
        to install (the pinned versions of :data:`PINS`, libllvm19) and the tail of the
        child's output.
    """
    ok, msg = _probe()
    return (ok, msg) if reason else ok


def _mitsuba():
    import mitsuba as mi

    if mi.variant() != VARIANT:
        mi.set_variant(VARIANT)
    import drjit as dr
    import mitransient  # noqa: F401  (registers the transient plugins)

    return mi, dr


def _uniform_width(edges):
    d = np.diff(edges)
    if d.size == 0 or np.any(d <= 0):
        raise ValueError("bin_edges must be strictly increasing, at least one bin")
    if not np.allclose(d, d[0], rtol=1e-9, atol=0.0):
        raise ValueError("mitransient's film has uniform time bins: bin_edges must be "
                         "evenly spaced")
    return float((edges[-1] - edges[0]) / d.size)


def mitransient_profile(vertices, faces, view, bin_edges, *, reflectance=0.5, spp=64,
                        film=(256, 256), seed=0, sampler="stratified", two_sided=True):
    """Range profile of a Lambertian mesh rendered with mitransient, in meshladar's units.

    The mesh (flat facets, a ``diffuse`` BSDF of reflectance ρ, wrapped in ``twosided``
    unless ``two_sided=False``, matching meshladar's default ``back_faces="two-sided"``) is
    seen by an orthographic sensor looking along −w and lit by a ``directional`` emitter of
    irradiance 1 travelling along −w (monostatic, collocated), with ``transient_path``
    at ``max_depth=2`` (single bounce, as meshladar). Returned per range bin:
    Σ_pixels film × pixel area = ∫ F cos θ_i cos θ_r dA, F = ρ/π: meshladar's
    ``radiometry="power"`` (Eq. 8 of the paper has one cos θ fewer).

    Path-length mapping. With this sensor and emitter mitransient's optical path length of
    a point p is its one-way distance from the sensor's near plane plus a constant: the
    directional emitter counts 2 × (the scene's bounding-sphere radius) × (1 + RayEpsilon)
    for the light's leg (RayEpsilon = 1500 float32 ulps = 8.94e-5), whatever p. With
    meshladar's range r = −p·w and r_near the range of the near plane,
    ``opl = r − r_near + 2 R_bs (1 + RayEpsilon)``; the film is set to
    ``start_opl = bin_edges[0] − r_near + 2 R_bs (1 + RayEpsilon)`` and
    ``bin_width_opl`` = the range bin width (not twice it: the light's leg is constant).
    R_bs is read from the loaded Mitsuba scene (its shapes' bounding box).

    Parameters
    ----------
    vertices, faces : (n, 3) float, (m, 3) int
        The mesh (float32 inside Mitsuba).
    view : (3,) array_like
        w, from the scene toward the sensor (normalised here).
    bin_edges : (n_bins + 1,) array_like
        Increasing, evenly spaced range edges (mitransient's bins are uniform).
    reflectance : float
        ρ of the diffuse BSDF.
    spp : int
        Samples per pixel (rounded up to a square for the stratified samplers, which
        stratify a square grid per pixel; ``info["spp"]`` is the count used).
    film : (nx, ny)
        Pixels; square pixels, the frame covering the mesh's bounding sphere.
    seed : int
        The sampler's seed.
    sampler : str
        Mitsuba sampler plugin ("stratified" converges faster than "independent" here).
    two_sided : bool
        Wrap the BSDF in ``twosided`` (back faces reflect as front faces).

    Returns
    -------
    profile : (n_bins,) ndarray, float64
    info : dict
        ``seconds`` (load + render), ``spp``, ``samples`` (pixels × spp), ``variant``,
        ``film``, ``pixel_area``, ``sampler``, ``seed`` and ``mapping`` (``start_opl``,
        ``bin_width_opl``, ``r_near``, ``bounding_radius``, ``ray_epsilon``, ``formula``).
    """
    v, f, w, edges = _checked(vertices, faces, view, bin_edges)
    width, (nx, ny) = _uniform_width(edges), (int(film[0]), int(film[1]))
    spp = _samples(spp, sampler)
    mi, dr = _mitsuba()
    t0 = time.perf_counter()
    mesh = _target(mi, v, f, reflectance, two_sided)
    fr = _frame(mi, v, w, nx, ny)
    mapping = _opl_mapping(mi, mesh, w, fr, edges, width)
    r_bs = mapping["bounding_radius"]
    scene = _transient_scene(mi, mesh, w, fr, {
        "sampler": {"type": sampler, "sample_count": spp, "seed": int(seed)},
        "film": {"type": "transient_hdr_film", "width": nx, "height": ny,
                 "temporal_bins": len(edges) - 1, "bin_width_opl": width,
                 "start_opl": mapping["start_opl"], "rfilter": {"type": "box"}}})
    if abs(float(scene.bbox().bounding_sphere().radius) - r_bs) > 1e-6 * max(r_bs, 1.0):
        raise RuntimeError("the scene's bounding sphere differs from the mesh's: the "
                           "path-length mapping would be off")
    _, transient = mi.render(scene, spp=spp, seed=int(seed))
    arr = np.array(transient, dtype=np.float64)
    dr.sync_thread()
    seconds = time.perf_counter() - t0
    pixel_area = (2.0 * fr.h / nx) ** 2
    # (x, y, t, channels) -> per bin
    profile = arr.reshape(-1, len(edges) - 1, arr.shape[-1])[..., 0].sum(axis=0) * pixel_area
    info = {"seconds": seconds, "spp": spp, "samples": nx * ny * spp, "variant": VARIANT,
            "film": (nx, ny), "pixel_area": pixel_area, "sampler": sampler, "seed": int(seed),
            "mapping": mapping}
    return profile, info


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _time_for(points, target):
    """Time to reach ``target`` error from (seconds, error) points, log-log interpolated
    between the first two successive runs that bracket it; None if no run reached it (no
    extrapolation)."""
    pts = sorted(points)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > e1:
            s = np.log(t1 / t0) / np.log(e1 / e0)
            return float(t0 * (target / e0) ** s)
    if pts and pts[0][1] <= target:
        return float(pts[0][0])
    return None


def bench_time_to_accuracy(*, subdivisions=6, view=(0.3, 0.5, 0.8), n_bins=64,
                           reflectance=0.5, ray_spacings=(4e-3, 2e-3, 1e-3, 5e-4, 3e-4),
                           spps=(4, 16, 64, 256, 1024), film=(256, 256), seeds=(0, 1),
                           targets=(1e-3, 1e-4)):
    """Time each tool needs for a given relative L2 accuracy of a range profile.

    Target: a unit Lambertian icosphere (``subdivisions``; 6 is 81,920 faces) seen from
    ``view``, ``n_bins`` bins over its visible depth, ``radiometry="power"``. Errors are
    against :func:`convex_power_profile` of the same mesh (exact: no faceting error, so
    only the sampling error of each tool is measured), averaged (RMS) over ``seeds``;
    times are warm (each tool's first, compiling run is discarded). meshladar runs
    ``ml.simulate(model="mesh", radiometry="power", normals="flat")`` at each ray spacing;
    mitransient runs :func:`mitransient_profile` at each spp on ``film``.

    Returns a dict: ``meshladar`` and ``mitransient`` lists of runs (knob, rays or samples,
    seconds, error), ``time_to`` {target: {tool: seconds or None}}, ``faces``,
    ``closed_form_error`` (the faceting error of the mesh itself against the sphere) and
    the settings. ``available()`` false: only meshladar's side, mitransient's left empty.

    About 100 s on 2 cores with the defaults (mitransient's 1024 spp runs are 26 s each).
    Measured there (Dec 2026, shared machine): 1e-3 in 0.08 s (meshladar, 1M rays) against
    1.1 s (mitransient, ~20 spp), 1e-4 in 2.7 s (~25M rays) against 14 s (~500 spp); per
    sample both tools are about equally accurate (16M rays 1.4e-4, 16.8M samples 1.6e-4).

    Parameters
    ----------
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6); the sphere has radius 1 at the origin.
    view : (3,) array_like, keyword-only
        w, toward the sensor (normalised here; default (0.3, 0.5, 0.8)).
    n_bins : int, keyword-only
        Range bins over [−1, 0], the sphere's near half (default 64).
    reflectance : float, keyword-only
        ρ of the Lambertian coating (default 0.5).
    ray_spacings : sequence of float, keyword-only
        meshladar's ray spacings, scene units (default 4e-3 to 3e-4); the first is also
        the warm-up run's.
    spps : sequence of int, keyword-only
        mitransient's samples per pixel (default 4 to 1024).
    film : (nx, ny), keyword-only
        mitransient's film in pixels (default (256, 256)).
    seeds : sequence of int, keyword-only
        Seeds of each setting's runs (default (0, 1)): times are their mean, errors their
        RMS.
    targets : sequence of float, keyword-only
        Relative L2 errors to find each tool's time for (default (1e-3, 1e-4)).

    Returns
    -------
    dict
        ``meshladar``: one dict per ray spacing (``ray_spacing``, ``rays``, ``seconds``,
        ``error``); ``mitransient``: one per spp (``spp``, ``samples``, ``seconds``,
        ``error``), empty when :func:`available` is false; ``time_to``: target → {tool:
        seconds, or None when no run reached it}, log-log interpolated between the runs
        that bracket it (tools without runs left out); ``faces``, ``n_bins``, ``view``
        (normalised), ``film``, ``seeds``; ``closed_form_error``: the mesh's own relative
        L2 error against :func:`sphere_power_profile`.
    """
    sphere = _sphere(subdivisions, view, n_bins, reflectance)
    runs = {"meshladar": _meshladar_runs(sphere, ray_spacings, seeds), "mitransient": []}
    if available():
        runs["mitransient"] = _mitransient_runs(sphere, reflectance, spps, film, seeds)
    time_to = {}
    for target in targets:
        time_to[target] = {tool: _time_for([(r["seconds"], r["error"]) for r in rs], target)
                           for tool, rs in runs.items() if rs}
    return {**runs, "time_to": time_to, "faces": len(sphere.f), "n_bins": n_bins,
            "view": sphere.w.tolist(), "film": tuple(film), "seeds": tuple(seeds),
            "closed_form_error": _rel(sphere.exact, sphere_power_profile(
                sphere.edges, 1.0, reflectance, sphere.top))}


class _Sphere(NamedTuple):
    """The target of :func:`bench_time_to_accuracy`: the icosphere's vertices ``v`` and faces
    ``f``, the unit view ``w``, the range ``edges`` from its nearest point ``top``, its
    ``exact`` profile (:func:`convex_power_profile`), and meshladar's ``scene`` and
    ``ladar`` of it."""

    v: np.ndarray
    f: np.ndarray
    w: np.ndarray
    top: float
    edges: np.ndarray
    exact: np.ndarray
    scene: Scene
    ladar: Ladar


def _sphere(subdivisions, view, n_bins, reflectance):
    """The unit Lambertian icosphere at the origin seen from ``view``: a :class:`_Sphere`."""
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    w = np.asarray(view, dtype=np.float64)
    w = w / np.linalg.norm(w)
    top = -1.0                                        # the sphere's (the mesh's within 1e-3)
    edges = np.linspace(top, 0.0, n_bins + 1)
    exact = convex_power_profile(v, f, w, edges, reflectance)
    scene = Scene.from_mesh(mesh, lambertian(reflectance))
    ladar = Ladar(None, edges, view_vectors=w[None])
    return _Sphere(v, f, w, top, edges, exact, scene, ladar)


def _meshladar_runs(sphere, ray_spacings, seeds):
    """meshladar's runs on ``sphere``, after a warm-up run: one dict per ray spacing, its
    seeds' mean time and RMS error."""

    def ml_run(spacing, seed):
        t = time.perf_counter()
        s = simulate(sphere.scene, sphere.ladar, model="mesh", radiometry="power",
                     normals="flat", ray_spacing=spacing, seed=seed)
        return time.perf_counter() - t, s.values[0], int(np.sum(s.info.get("rays", 0)))

    ml_run(ray_spacings[0], 0)                                  # warm: build, compile
    runs = []
    for sp in ray_spacings:
        ts, errs, n = [], [], 0
        for sd in seeds:
            t, p, n = ml_run(sp, sd)
            ts.append(t)
            errs.append(_rel(p, sphere.exact))
        runs.append({"ray_spacing": sp, "rays": n, "seconds": float(np.mean(ts)),
                     "error": float(np.sqrt(np.mean(np.square(errs))))})
    return runs


def _mitransient_runs(sphere, reflectance, spps, film, seeds):
    """mitransient's runs on ``sphere``, after a warm-up render: one dict per spp, its
    seeds' mean time and RMS error."""
    v, f, w, edges = sphere.v, sphere.f, sphere.w, sphere.edges
    mitransient_profile(v, f, w, edges, reflectance=reflectance, spp=1, film=(8, 8))
    runs = []
    for spp in spps:
        ts, errs, n = [], [], 0
        for sd in seeds:
            p, info = mitransient_profile(v, f, w, edges, reflectance=reflectance, spp=spp,
                                          film=film, seed=sd)
            ts.append(info["seconds"])
            errs.append(_rel(p, sphere.exact))
            n = info["samples"]
        runs.append({"spp": spp, "samples": n, "seconds": float(np.mean(ts)),
                     "error": float(np.sqrt(np.mean(np.square(errs))))})
    return runs
