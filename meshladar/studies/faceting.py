"""Faceting-versus-analytic studies: how mesh resolution, normals, rays and pixels trade speed
for accuracy, measured against the exact profiles of ``model="analytic"``.

:func:`faceting_study` sweeps, for the paper's phantoms (disk, ellipse, disk pair) and
coatings (dark gray, aluminium, diffuse b = 0.99, specular e = 0.007): tessellation segments,
normal mode (flat / smooth / exact), rays per bin, binning (point / footprint), and the pixel
model's pixel size. Each point records the sinogram error against the analytic sinogram
(relative L2 and relative max), the error of its FBP image against the FBP of the analytic
sinogram (relative L2), and the wall time of the forward run.

Error sources are separated by the sweep's design:

* ``position``: exact normals, footprint binning, dense rays; segments vary. Only the
  facets' positions (silhouette, ranges) differ from the true shape.
* ``normal``: flat normals, same rays; segments vary. Adds the facets' normal error.
* ``rays``: exact normals on the finest mesh; rays per bin vary (point and footprint).
* ``pixel``: the pixel model; pixel size varies.

:func:`convergence_orders` fits the slope of log error against log resolution (segments,
rays per bin, 1/pixel size) on each series' finest points and finds where a series breaks:
the glint lobe at e = 0.007 is narrower than a facet's angular step 2π/N until N ≳ π/e, so
flat facets miss it entirely below that.
"""

from __future__ import annotations

import csv
import functools
import io as _io
import json
import os
import time
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import __version__
from .. import phantoms as _phantoms
from .. import materials as _materials
from .._validate import check_path
from ..brdf import SandfordRobertson
from ..errors import EnergyConservationWarning, MeshladarWarning, ParameterError
from ..forward import simulate
from ..forward.sampling import checked_by_caller
from ..ladar import Ladar
from ..precision import TINY
from ..reconstruct import fbp
from ..io import save_result, write_text_atomic
from ..runs import RunFolder
from ..sinogram import Sinogram
from ..stream import Progress

__all__ = ["PHANTOMS", "COATINGS", "SETTINGS", "faceting_study", "convergence_orders",
           "study_scene"]

#: The paper's phantoms, as builders taking a coating (from the phantom library's specs).
PHANTOMS = {name: functools.partial(_phantoms.scene, name)
            for name in ("disk", "ellipse", "disk_pair")}


def _diffuse_b099():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EnergyConservationWarning)
        return SandfordRobertson(1.0, 0.0, 0.99, 1.0, lobes="diffuse", name="diffuse_b0.99")


#: Coatings of the study: the paper's two and its two extremes.
COATINGS = {
    "dark_gray": _materials.DARK_GRAY,
    "aluminum": _materials.ALUMINUM,
    "diffuse_b0.99": _diffuse_b099(),
    "specular_e0.007": _materials.glint(0.007, name="specular_e0.007"),
}

#: Sweep settings. "quick" runs in about a minute (36 views); "full" is the paper's 360 views
#: with segments to 4096 (about 25 minutes on two cores; see README).
SETTINGS = {
    "quick": {"views": 36, "segments": [8, 32, 128, 512, 2048], "rays_per_bin": [1, 2, 4, 8],
              "dense_rays": 8, "pixel_sizes": [0.01, 0.005, 0.0025], "image_size": 96},
    "full": {"views": 360, "segments": [8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096],
             "rays_per_bin": [1, 2, 4, 8, 16, 32], "dense_rays": 16,
             "pixel_sizes": [0.02, 0.01, 0.005, 0.0025, 0.00125], "image_size": 256},
}


def study_scene(phantom, coating):
    """The scene of a study point: a packaged phantom with one coating on every shape.

    Parameters
    ----------
    phantom : str
        A name of :data:`PHANTOMS`: ``"disk"``, ``"ellipse"`` or ``"disk_pair"``.
    coating : str
        A name of :data:`COATINGS`: ``"dark_gray"``, ``"aluminum"``, ``"diffuse_b0.99"``
        or ``"specular_e0.007"``.

    Returns
    -------
    Scene
        The phantom's analytic scene (:func:`meshladar.phantoms.scene`), every shape in
        the coating.

    Raises
    ------
    ParameterError
        When ``phantom`` or ``coating`` is not one of those names.
    """
    if phantom not in PHANTOMS:
        raise ParameterError(f"phantom must be one of {tuple(PHANTOMS)}; got {phantom!r}")
    if coating not in COATINGS:
        raise ParameterError(f"coating must be one of {tuple(COATINGS)}; got {coating!r}")
    return PHANTOMS[phantom](COATINGS[coating])


def _fbp(sino, size):
    """FBP for a study: a quick study's few views streak the analytic and the mesh images
    alike, which the comparison cancels, so fbp's undersampling warning is not repeated."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".* views are too few for the",
                                category=MeshladarWarning)
        return fbp(sino, size=size, extent=1.0)


def _errors(values, ref, ref_image, ladar, size):
    diff = values - ref.values
    norm = np.linalg.norm(ref.values)

    image = _fbp(Sinogram(values, angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges), size)
    return {"rel_l2": float(np.linalg.norm(diff) / norm),
            "rel_max": float(np.max(np.abs(diff)) / np.max(np.abs(ref.values))),
            "image_rel_l2": float(np.linalg.norm(image.values - ref_image.values)
                                  / np.linalg.norm(ref_image.values))}


def faceting_study(setting="quick", *, phantoms=None, coatings=None, progress=False,
                   executor=None, run_dir=None):
    """Run the faceting sweep against the analytic model.

    Parameters
    ----------
    setting : {"quick", "full"}
        The sweep's size (:data:`SETTINGS`): views, segments, rays per bin, pixel sizes and
        image size. "quick" runs in about a minute on 2 cores.
    phantoms, coatings : list of str, optional
        Names from :data:`PHANTOMS` and :data:`COATINGS` (default all).
    progress : bool
        A progress bar over the study's points, on a terminal only.
    executor : concurrent.futures.Executor, optional
        Runs the mesh points' chunks of views (e.g. a Dask one); wall times include it.
    run_dir : path, optional
        Makes the study resumable: each finished point is kept there (checksummed), and
        running the same study again computes only the missing points.

    Returns
    -------
    dict
        ``rows``: one dict per point (phantom, coating, series, segments, normals,
        rays_per_bin, footprint, pixel_size, rel_l2, rel_max, image_rel_l2, seconds,
        analytic_seconds);
        ``setting``; ``config`` (its :data:`SETTINGS` entry); ``orders``
        (:func:`convergence_orders` of the rows); ``examples``: for each phantom and
        coating, the analytic sinogram, a coarse flat mesh's (``segments[1]``) sinogram
        and both FBP images, for the difference figures; ``bin_edges`` and
        ``angles_deg`` of the ladar (the paper's A/256 bins, ``views`` views evenly over
        360°).

    Raises
    ------
    ParameterError
        When ``setting`` is not a key of :data:`SETTINGS`, ``phantoms`` or ``coatings`` is
        not a list or tuple (or holds an unknown name), or ``run_dir`` is not a path.
    """
    cfg, phantoms, coatings = _checked(setting, phantoms, coatings, run_dir)
    ladar = Ladar.paper(angles_deg=np.arange(0.0, 360.0, 360.0 / cfg["views"]))
    plan = _plan(cfg)
    n_points = len(phantoms) * len(coatings) * len(plan)
    bar = Progress(n_points, "study points", enabled=progress)
    folder = _run_folder(run_dir, setting, cfg, phantoms, coatings, n_points)
    rows, examples = [], {}
    index = 0
    for ph in phantoms:
        for co in coatings:
            run = _Run(study_scene(ph, co), ladar, cfg["image_size"], executor, {}, {})
            for pt in plan:
                row = {"phantom": ph, "coating": co, **pt._asdict()}
                example = pt.series == "normal" and pt.segments == cfg["segments"][1]
                saved = folder.load(index) if folder is not None else None
                if saved is None:
                    saved = _measure(run, pt, example)
                    if folder is not None:
                        folder.save(index, saved)
                row.update({k: float(saved[k]) for k in ("rel_l2", "rel_max", "image_rel_l2",
                                                         "seconds", "analytic_seconds")})
                rows.append(row)
                if example:
                    examples[f"{ph}/{co}"] = {k: np.asarray(saved[k]) for k in
                                              ("analytic", "mesh", "analytic_image",
                                               "mesh_image")}
                    examples[f"{ph}/{co}"]["segments"] = pt.segments
                index += 1
                bar.update()
    bar.close()
    return {"setting": setting, "config": cfg, "rows": rows,
            "orders": convergence_orders(rows), "examples": examples,
            "bin_edges": ladar.bin_edges, "angles_deg": ladar.angles_deg}


def _checked(setting, phantoms, coatings, run_dir):
    """The study's arguments checked: (its :data:`SETTINGS` entry, phantom names, coating
    names), the names defaulting to all."""
    if setting not in SETTINGS:
        raise ParameterError(f"setting must be one of {tuple(SETTINGS)}; got {setting!r}")
    for arg, value in (("phantoms", phantoms), ("coatings", coatings)):
        if value is not None and not isinstance(value, (list, tuple)):
            raise ParameterError(f"{arg} must be a list of names; got {value!r}")
    if run_dir is not None:
        check_path("run_dir", run_dir)
    phantoms = list(PHANTOMS) if phantoms is None else list(phantoms)
    coatings = list(COATINGS) if coatings is None else list(coatings)
    return SETTINGS[setting], phantoms, coatings


def _run_folder(run_dir, setting, cfg, phantoms, coatings, n_points):
    """The resumable study's folder of ``n_points`` finished points (None without
    ``run_dir``), keyed by everything that decides the points' values."""
    if run_dir is None:
        return None
    return RunFolder(run_dir, {"kind": "faceting_study", "setting": setting,
                               "config": cfg, "phantoms": phantoms,
                               "coatings": coatings, "version": __version__},
                     n_points)


class _Point(NamedTuple):
    """One point of a series: the row's settings."""

    series: str
    segments: int | None
    normals: str | None
    rays_per_bin: int | None
    footprint: bool | None
    pixel_size: float | None


@dataclass(frozen=True)
class _Run:
    """A phantom and coating's points: the scene, the ladar, the image size, the executor,
    and the meshes and the analytic reference, each made on first need."""

    scene: object
    ladar: object
    size: int
    executor: object
    meshes: dict
    reference: dict


def _plan(cfg):
    seg, rpb, dense = cfg["segments"], cfg["rays_per_bin"], cfg["dense_rays"]
    return ([_Point("position", n, "exact", dense, True, None) for n in seg]
            + [_Point("normal", n, "flat", dense, True, None) for n in seg]
            + [_Point("smooth", n, "smooth", dense, True, None) for n in seg]
            + [_Point("rays", seg[-1], "exact", r, False, None) for r in rpb]
            + [_Point("rays_footprint", seg[-1], "exact", r, True, None) for r in rpb]
            + [_Point("pixel", None, None, None, None, p) for p in cfg["pixel_sizes"]])


def _reference(run):
    """The analytic sinogram, its FBP image and its time, computed once per run."""
    if not run.reference:
        t0 = time.perf_counter()
        ref = simulate(run.scene, run.ladar)
        t_ref = time.perf_counter() - t0
        run.reference.update(sino=ref, seconds=t_ref, image=_fbp(ref, run.size))
    return run.reference


def _simulate_point(run, pt):
    if pt.series == "pixel":
        return simulate(run.scene, run.ladar, model="pixel", pixel_size=pt.pixel_size)
    if pt.segments not in run.meshes:
        run.meshes[pt.segments] = run.scene.tessellate(pt.segments)
    par = {"executor": run.executor} if run.executor is not None else {"jobs": 1}
    with checked_by_caller():       # the faceting and sampling errors are what it measures
        return simulate(run.meshes[pt.segments], run.ladar, model="mesh",
                        normals=pt.normals, rays_per_bin=pt.rays_per_bin,
                        footprint=pt.footprint, **par)


def _measure(run, pt, example):
    """A point's errors and times (and, for the example, its sinograms and images)."""
    ref = _reference(run)
    t0 = time.perf_counter()
    sino = _simulate_point(run, pt)
    dt = time.perf_counter() - t0
    err = _errors(sino.values, ref["sino"], ref["image"], run.ladar, run.size)
    saved = {k: np.float64(v) for k, v in err.items()}
    saved["seconds"] = np.float64(dt)
    saved["analytic_seconds"] = np.float64(ref["seconds"])
    if example:
        saved.update({"analytic": ref["sino"].values, "mesh": sino.values,
                      "analytic_image": ref["image"].values,
                      "mesh_image": _fbp(sino, run.size).values})
    return saved


def _resolution(row):
    s = row["series"]
    if s == "pixel":
        return 1.0 / row["pixel_size"]
    if s.startswith("rays"):
        return float(row["rays_per_bin"])
    return float(row["segments"])


def convergence_orders(rows, *, tail=3):
    """Fitted convergence order of each series per phantom and coating.

    The order is −slope of log(rel_l2) against log(resolution) (segments; rays per bin;
    1/pixel size) over the ``tail`` points that end where the series reaches its floor: the
    first point within 2× of its finest error (later points only measure the floor set by
    what the series holds fixed). ``floor`` says whether the finest two points differ by
    less than 30%. ``break_at`` is the first resolution at which the error falls below half
    its coarsest value (where a series starts converging: large for flat facets on a narrow
    glint).

    Parameters
    ----------
    rows : list of dict
        :func:`faceting_study`'s ``rows``.
    tail : int
        Points in each fit.

    Returns
    -------
    list of dict
        One per phantom, coating and series: ``order``, ``break_at``, ``floor``,
        ``finest_rel_l2``, ``coarsest_rel_l2``.
    """
    out = []
    keys = sorted({(r["phantom"], r["coating"], r["series"]) for r in rows})
    for ph, co, s in keys:
        sel = [r for r in rows if (r["phantom"], r["coating"], r["series"]) == (ph, co, s)]
        sel.sort(key=_resolution)
        err = np.array([max(r["rel_l2"], TINY) for r in sel])
        x = np.log([_resolution(r) for r in sel])
        y = np.log(err)
        end = int(np.argmax(err <= 2.0 * err[-1])) + 1          # first point near the floor
        lo = max(0, end - tail)
        slope = float(np.polyfit(x[lo:end], y[lo:end], 1)[0]) if end - lo >= 2 \
            else float("nan")
        first = sel[0]["rel_l2"]
        brk = next((_resolution(r) for r in sel if r["rel_l2"] < 0.5 * first), None)
        floor = bool(len(err) >= 2 and err[-2] < 1.3 * err[-1])
        out.append({"phantom": ph, "coating": co, "series": s, "order": -slope,
                    "break_at": brk, "floor": floor, "finest_rel_l2": sel[-1]["rel_l2"],
                    "coarsest_rel_l2": first})
    return out


def save_study(result, outdir):
    """Write ``faceting.csv``, ``faceting.json`` and ``faceting_examples.npz`` atomically.

    Parameters
    ----------
    result : dict
        What :func:`faceting_study` returns.
    outdir : path
        The folder (created if missing); files already there are replaced atomically.

    Returns
    -------
    list of str
        The paths written.
    """
    if not isinstance(result, dict) or "rows" not in result:
        raise ParameterError(f"result must be what faceting_study returns (a dict with rows); "
                             f"got {type(result).__name__}")
    outdir = check_path("outdir", outdir)
    os.makedirs(outdir, exist_ok=True)
    cols = ["phantom", "coating", "series", "segments", "normals", "rays_per_bin", "footprint",
            "pixel_size", "rel_l2", "rel_max", "image_rel_l2", "seconds", "analytic_seconds"]
    buf = _io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, extrasaction="ignore")
    w.writeheader()
    for r in result["rows"]:
        w.writerow(r)
    write_text_atomic(os.path.join(outdir, "faceting.csv"), buf.getvalue())
    doc = {k: result[k] for k in ("setting", "config", "rows", "orders")}
    write_text_atomic(os.path.join(outdir, "faceting.json"), json.dumps(doc, indent=1))
    arrays = {"bin_edges": result["bin_edges"], "angles_deg": result["angles_deg"]}
    for key, ex in result["examples"].items():
        for name in ("analytic", "mesh", "analytic_image", "mesh_image"):
            arrays[f"{key}/{name}"] = ex[name]
    meta = {"examples": {k: {"segments": v["segments"]} for k, v in result["examples"].items()},
            "setting": result["setting"]}
    save_result(os.path.join(outdir, "faceting_examples.npz"), arrays, meta)
    return [os.path.join(outdir, n) for n in ("faceting.csv", "faceting.json",
                                              "faceting_examples.npz")]


def _fmt(x):
    return "-" if x is None else (f"{x:.3g}" if isinstance(x, float) else str(x))


def report(result) -> str:
    """A plain-text summary: the convergence orders and break points of every series.

    Parameters
    ----------
    result : dict
        What :func:`faceting_study` returns (its ``setting``, ``rows`` and ``orders`` are
        read).

    Returns
    -------
    str
        A title line, a header and one line per series (phantom, coating, series, order,
        break point, coarsest and finest relative L2 error, "yes" when it reached its
        floor), joined by newlines.
    """
    lines = [f"faceting study ({result['setting']}): {len(result['rows'])} points",
             f"{'phantom':<10} {'coating':<16} {'series':<15} {'order':>6} {'breaks at':>9} "
             f"{'coarsest':>9} {'finest':>9} floor"]
    for o in result["orders"]:
        lines.append(f"{o['phantom']:<10} {o['coating']:<16} {o['series']:<15} "
                     f"{o['order']:6.2f} {_fmt(o['break_at']):>9} "
                     f"{o['coarsest_rel_l2']:9.2e} {o['finest_rel_l2']:9.2e} "
                     f"{'yes' if o['floor'] else ''}")
    return "\n".join(lines)
