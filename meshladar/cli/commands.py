"""The command line's small commands: demo, materials, paper, view, study, bench. Each body
only calls the API (and :mod:`meshladar.plotting`'s door for figures)."""

from __future__ import annotations

import csv
import io
import json
import os
from typing import NamedTuple

import numpy as np

import meshladar as _ml   # its studies load when a study, paper or bench command runs

from .. import materials, phantoms, plotting
from .._validate import check_size
from ..errors import ParameterError
from ..io import write_text_atomic
from ..scan.files import read_hdf5, read_las
from ..scan.npz import read_npz
from ..scan.formats import points_format
from .checks import check_outdir, check_output
from .simulate import load_scene
from .words import flag_words

__all__ = ["cmd_demo", "cmd_materials", "cmd_paper", "cmd_view", "view_words", "cmd_study",
           "cmd_bench", "DEMO_ANGLES_DEG"]

DEMO_ANGLES_DEG = (0.0, 1.0, 5.0, 10.0, 30.0, 60.0, 85.0, 90.0)


def cmd_demo(args) -> int:
    """Print the paper's two coatings' monostatic BRDF at a few incidence angles.

    Parameters
    ----------
    args : argparse.Namespace
        ``angles_deg``: the incidence angles θ in degrees (list of float). For dark gray
        and aluminium, each angle's row holds F [1/sr], F cos θ [1/sr] and the specular
        reflectance ρ_s(θ). At grazing incidence (θ = 90° + k·180°, where the coating
        still returns light) F grows without bound as 1/cos θ: its column says
        ``unbounded`` (a float cos 90° of 6e-17 would print ~1e14) and a note follows;
        F cos θ, the weight the sinogram uses, stays bounded. An angle that 3 decimals
        would round is printed with up to 10 significant digits.

    Returns
    -------
    int
        0, the exit status.
    """
    angles = np.array(args.angles_deg, dtype=np.float64)
    theta = np.deg2rad(angles)
    print("Sandford-Robertson BRDF, monostatic (collocated ladar), paper coatings at 1 um")
    for m in (materials.DARK_GRAY, materials.ALUMINUM):
        print(f"\n{m.name}: rho_d={m.rho_d:g} epsilon={m.epsilon:g} b={m.b:g} e={m.e:g}"
              f"  G(b)={m.G:.6f}")
        print(f"  {'theta [deg]':>11}  {'F [1/sr]':>12}  {'F cos(theta) [1/sr]':>20}"
              f"  {'rho_s(theta)':>12}")
        f = m.monostatic(theta)
        fc = m.monostatic(theta, projected=True)
        rs = m.specular_reflectance(theta)
        grazing = (np.mod(angles, 180.0) == 90.0) & (fc != 0.0)
        for a, fa, fca, rsa, g in zip(angles, f, fc, rs, grazing):
            shown = "unbounded" if g else f"{fa:.6g}"
            print(f"  {_demo_angle(a):>11}  {shown:>12}  {fca:20.6g}  {rsa:12.6f}")
        if grazing.any():
            print("  F is unbounded at grazing incidence (it grows as 1/cos(theta)); "
                  "F cos(theta) stays bounded")
    return 0


def _demo_angle(a):
    """An angle in degrees with 3 decimals, or up to 10 significant digits where 3 would
    round it (89.9999999 is not 90) or
    the number is huge."""
    return f"{a:.3f}" if abs(a) < 1e9 and float(f"{a:.3f}") == a else f"{a:.10g}"


def cmd_materials(args) -> int:
    """List a coating table (the packaged one by default).

    Parameters
    ----------
    args : argparse.Namespace
        ``table``: the path of a TOML material table, or None for the packaged one
        (:func:`meshladar.phantoms.materials`). Each coating's row holds its lobes, ρ_d, ε,
        b, e, G(b) and its monostatic F(0) [1/sr].

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    MeshladarError
        When the table cannot be read or is not a valid material table
        (:func:`meshladar.materials.load_table`).
    """
    table = phantoms.materials() if args.table is None else materials.load_table(args.table)
    print(f"{'name':<14} {'lobes':<9} {'rho_d':>7} {'epsilon':>8} {'b':>6} {'e':>7}"
          f" {'G(b)':>8} {'F(0) [1/sr]':>12}")
    for name, m in table.items():
        print(f"{name:<14} {m.lobes:<9} {m.rho_d:7.4g} {m.epsilon:8.4g} {m.b:6.4g} {m.e:7.4g}"
              f" {m.G:8.5f} {m.monostatic(0.0):12.5g}")
    return 0


def cmd_paper(args) -> int:
    """Reproduce the paper's Figs 5-11: PNGs, a saved result and the findings' numbers.

    Runs :func:`meshladar.viz.paper.reproduce`: ``paper_result.npz`` and ``fig05.png`` to
    ``fig11.png`` in the folder; prints each finding's value and the paths written.

    Parameters
    ----------
    args : argparse.Namespace
        ``outdir``: the folder (created if missing); ``size``: the reconstructions' side in
        pixels (int).

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        When ``outdir`` is not a folder name, ``size`` is below
        :data:`meshladar.studies.paper.MIN_SIZE`, or a ``size`` × ``size`` image (24 bytes
        a pixel) would exceed the 4 GiB meshladar allocates at once; all before any work.
    ImportError
        When matplotlib is not installed (checked before the work).
    """
    check_outdir(args.outdir)
    minimum = _ml.studies.paper.MIN_SIZE
    if args.size < minimum:
        raise ParameterError(f"--size must be at least {minimum}: the paper's findings hold, "
                             "each within its tolerance of its 512x512 figure "
                             f"(docs/guide/paper.md), from {minimum} pixels a side up; got "
                             f"{args.size}")
    check_size("--size", float(args.size) ** 2, 8 * 3, f"a {args.size} x {args.size} image",
               "use a smaller --size")
    plotting.require("matplotlib")              # before the work, not after it
    paths, metrics = plotting.viz("paper").reproduce(args.outdir, size=args.size)
    print(f"Jin & Levine (2009) Figs 5-11 reproduced in {args.outdir}/ "
          "(analytic model, 360 views, A/256 bins)")
    print(f"  {'finding':<42} {'value':>10}")
    for key, value in metrics.items():
        print(f"  {key:<42} {value:10.4f}")
    for p in paths:
        print(f"  wrote {p}")
    return 0


def cmd_view(args) -> int:
    """Show a scene in 3-D coloured by its return for one view (or save a screenshot).

    Draws :func:`meshladar.viz.viewer.show_scene` with the scene's default ladar (a
    phantom's; none for a mesh).

    Parameters
    ----------
    args : argparse.Namespace
        The scene's options (``scene``, ``material``, ``coating``, ``materials``: see
        :func:`meshladar.cli.simulate.load_scene`); ``view_angle``: the view's angle about z
        in degrees (None: 90); ``screenshot``: a ``.png`` path to render off screen into,
        or None to open a window; ``log``: colour by log10 of the return; ``size``: the
        window's (width, height) in pixels; ``camera``: ``"oblique"`` or ``"view"`` (None:
        oblique); ``points``: a point cloud file (``meshladar scan``'s LAS, LAZ or HDF5)
        drawn over the scene by :func:`meshladar.viz.points.show_points`, coloured by
        ``color_by`` (None: intensity), or None; ``bounces``: with a number,
        :func:`meshladar.viz.bounce_view.show_bounces` instead (a mesh scene); ``quiet``:
        no "wrote" line. Options that do not apply to the drawing chosen are refused
        (:func:`check_view_options`).

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        When an option does not apply to what is drawn (:func:`check_view_options`), when
        ``screenshot`` is not a ``.png`` path or names an input, when the scene
        cannot be loaded, or when there is no display (neither ``DISPLAY`` nor
        ``WAYLAND_DISPLAY`` set) and no ``screenshot``.
    ImportError
        When pyvista is not installed (checked before the scene is loaded).
    """
    check_view_options(args)
    view_angle = 90.0 if args.view_angle is None else args.view_angle
    camera = args.camera or "oblique"
    if args.screenshot is not None:
        check_output(args.screenshot, (".png",), [args.scene, args.materials, args.points],
                     "--screenshot")
    cloud = None if args.points is None else _read_points(args.points)
    plotting.require("pyvista")                 # before loading the scene
    scene, default_ladar, _ = load_scene(args)
    if args.screenshot is None and not (os.environ.get("DISPLAY")
                                        or os.environ.get("WAYLAND_DISPLAY")):
        raise ParameterError("no display to open a window on: use --screenshot PNG")
    if args.bounces is not None:
        if not scene.is_mesh:
            raise ParameterError("--bounces views a mesh (a phantom's light stays in its "
                                 "plane); give a mesh file")
        plotting.viz("bounce_view").show_bounces(
            scene, view_angle_deg=view_angle, bounces=args.bounces,
            off_screen=args.screenshot is not None, screenshot=args.screenshot,
            window_size=args.size, camera=camera)
    elif args.points is not None:
        plotting.viz("points").show_points(
            cloud, scene if scene.is_mesh else None, color_by=args.color_by or "intensity",
            off_screen=args.screenshot is not None, screenshot=args.screenshot,
            window_size=args.size)
    else:
        plotting.viz("viewer").show_scene(
            scene, view_angle_deg=view_angle, ladar=default_ladar,
            off_screen=args.screenshot is not None, screenshot=args.screenshot,
            log_scale=args.log, window_size=args.size, camera=camera)
    if args.screenshot and not args.quiet:
        print(f"wrote {args.screenshot}")
    return 0


#: What each of view's drawings takes no option of: (the drawing's flag, why, the flags).
_VIEW_REFUSES = (
    ("--bounces", "faces are coloured by the order of bounces that dominates their return",
     ("--points", "--color-by", "--log")),
    ("--points", "an isometric camera frames the scene and its points, coloured by "
     "--color-by",
     ("--view-angle", "--camera", "--log")))


def check_view_options(args):
    """``view``'s options that do not apply to what is drawn are errors, never ignored:
    the bounces' view takes no points, colouring or log scale; the points' view no view
    angle, camera or log scale; ``--color-by`` colours the points only.

    Parameters
    ----------
    args : argparse.Namespace
        ``view``'s options (``bounces``, ``points``, ``color_by``, ``log``,
        ``view_angle``, ``camera``: None or False when not given).

    Raises
    ------
    ParameterError
        Naming the first option that does not apply and the one that rules it out.
    """
    given = {"--bounces": args.bounces is not None, "--points": args.points is not None,
             "--color-by": args.color_by is not None, "--log": bool(args.log),
             "--view-angle": args.view_angle is not None,
             "--camera": args.camera is not None}
    for mode, why, flags in _VIEW_REFUSES:
        refused = [f for f in flags if given[f]]
        if given[mode] and refused:
            raise ParameterError(f"{refused[0]} does not apply with {mode} ({why}); leave "
                                 f"{refused[0]} out")
    if given["--color-by"] and not given["--points"]:
        raise ParameterError(f"--color-by {args.color_by} colours the points of --points; "
                             "give --points FILE, or leave --color-by out (the scene is "
                             "coloured by its return)")


#: view's messages in its flags' words (:func:`.words.flag_words`): ``path`` is the point
#: file's (the readers' ``path: ...``).
view_words = flag_words({"color_by": "--color-by", "view_angle_deg": "--view-angle",
                         "path": "--points"}, ("color_by", "view_angle_deg"))


def _read_points(path):
    """A point cloud file (LAS/LAZ, HDF5 or .npz by extension; its errors' ``path`` is
    --points in :data:`view_words`)."""
    if points_format(path) == "LAS":              # another tool's too: its own fields
        return read_las(path, foreign=True)
    return {"HDF5": read_hdf5, "NPZ": read_npz}.get(points_format(path), read_las)(path)


def cmd_study(args) -> int:
    """Run a study and write its table (CSV/JSON), results and figures into a folder.

    The faceting study (:func:`meshladar.studies.faceting_study`) writes ``faceting.csv``,
    ``faceting.json``, ``faceting_examples.npz`` and its figures (``pareto.png``,
    ``error_vs_segments.png``, ``difference_<phantom>_<coating>.png``), keeps finished
    points in ``outdir/run`` (a rerun resumes) and prints its report. The tomography3d
    study (:func:`meshladar.studies.paper.run_3d`; quick: 600 views, 64³ voxels; full:
    2000 views, 128³) writes ``tomography3d.json`` and ``tomography3d.png``. The
    reconstruction study (:func:`meshladar.studies.reconstruction.run`) writes
    ``reconstruction.json``, ``reconstruction.csv`` and ``reconstruction.png``, and prints
    its table.

    Parameters
    ----------
    args : argparse.Namespace
        ``kind``: ``"faceting"``, ``"tomography3d"`` or ``"reconstruction"``; ``outdir``:
        the folder (created if missing); ``setting``: ``"quick"`` or ``"full"``;
        ``photons``, ``speckle``, ``background``: the reconstruction study's noise
        (photoelectrons in each sinogram's brightest bin, speckle cells per bin,
        background photoelectrons per bin), None when not given; ``quiet``: no progress
        bar (faceting study).

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        When ``outdir`` is not a folder name (or lies under a file); when ``photons``,
        ``speckle`` or ``background`` is given to a study other than reconstruction; when
        ``speckle`` or ``background`` is given without ``photons``; all before the work.
    ImportError
        When matplotlib is not installed (checked before the work).
    """
    noise = (("--photons", args.photons), ("--speckle", args.speckle),
             ("--background", args.background))
    for flag, value in noise:
        if value is not None and args.kind != "reconstruction":
            raise ParameterError(f"{flag} is an option of the reconstruction study; the "
                                 f"{args.kind} study does not use it")
        if value is not None and args.photons is None:
            raise ParameterError(f"{flag} needs --photons (the signal's scale in "
                                 "photoelectrons): give --photons N too")
    check_outdir(args.outdir)
    plotting.require("matplotlib")              # before the work, not after it
    if args.kind == "reconstruction":
        return _study_reconstruction(args)
    if args.kind == "tomography3d":
        return _study_3d(args)
    result = _ml.studies.faceting_study(args.setting, progress=not args.quiet,
                                    run_dir=os.path.join(args.outdir, "run"))
    files = _ml.studies.save_study(result, args.outdir)
    figs = plotting.viz("studies").draw(args.outdir)
    print(_ml.studies.report(result))
    for p in files + figs:
        print(f"  wrote {p}")
    return 0


#: The 3-D study's settings: (views, voxels per side, smoothing in bins, rays per bin).
class _Study3D(NamedTuple):
    """One setting of ``meshladar study tomography3d``:
    :func:`meshladar.studies.paper.run_3d`'s arguments."""

    views: int
    size: int
    smooth: float
    rays_per_bin: float


_STUDY_3D = {"quick": _Study3D(600, 64, 1.0, 1.0), "full": _Study3D(2000, 128, 1.0, 2.0)}


def _study_3d(args) -> int:
    """The paper's findings in 3-D (meshladar.studies.paper.run_3d): metrics as JSON, central slices
    of every volume as a PNG."""
    setting = _STUDY_3D[args.setting]
    views, size, smooth, rpb = setting.views, setting.size, setting.smooth, \
        setting.rays_per_bin
    metrics, volumes = _ml.studies.paper.run_3d(views=views, size=size, smooth=smooth,
                                    rays_per_bin=rpb)
    os.makedirs(args.outdir, exist_ok=True)
    doc = {"setting": args.setting, "views": views, "size": size, "smooth_bins": smooth,
           "rays_per_bin": rpb, "metrics": metrics}
    path = os.path.join(args.outdir, "tomography3d.json")
    write_text_atomic(path, json.dumps(doc, indent=2, sort_keys=True))
    (png,) = plotting.viz("studies").draw_tomography3d(volumes, args.outdir, views, size)
    print(f"3-D tomography study ({args.setting}: {views} views, {size}^3 voxels)")
    for key, value in metrics.items():
        print(f"  {key:<42} {value:10.4f}")
    print(f"  wrote {path}\n  wrote {png}")
    return 0


#: The reconstruction study's table columns.
_STUDY_COLUMNS = ["phantom", "spacing_deg", "method", "photons", "speckle_cells",
                  "background", "error", "clutter", "darkening", "visibility", "seconds"]


def _study_reconstruction(args) -> int:
    """The reconstruction study (meshladar.studies.reconstruction): its table as CSV and JSON,
    the 1° and 10° images of every method as a figure."""
    rows, images = _ml.studies.reconstruction.run(
        args.setting, photons=args.photons, speckle_cells=args.speckle,
        background=args.background or 0.0)
    os.makedirs(args.outdir, exist_ok=True)
    path = os.path.join(args.outdir, "reconstruction.json")
    write_text_atomic(path, json.dumps({"setting": args.setting, "rows": rows},
                                               indent=2))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=_STUDY_COLUMNS)
    writer.writeheader()
    for r in rows:
        writer.writerow({k: r.get(k, "") for k in _STUDY_COLUMNS})
    table = os.path.join(args.outdir, "reconstruction.csv")
    write_text_atomic(table, buf.getvalue())
    (png,) = plotting.viz("studies").draw_reconstruction(images, args.outdir)
    print(f"reconstruction study ({args.setting})")
    print("\n".join(_ml.studies.reconstruction.report(rows)))
    print(f"  wrote {path}\n  wrote {table}\n  wrote {png}")
    return 0


def cmd_bench(args) -> int:
    """Time the forward models and FBP against their peers (median of several runs).

    Prints :func:`meshladar.studies.bench.report` line by line, as each is measured.

    Parameters
    ----------
    args : argparse.Namespace
        ``repeats``: timed runs per case after one warm-up (int); ``full``: add the
        Mitsuba 3 + mitransient comparison, the streaming run and the Dask run (bool);
        ``gpu``: only the GPU line (bool).

    Returns
    -------
    int
        0, the exit status.
    """
    for line in _ml.studies.bench.report(repeats=args.repeats, full=args.full,
                                         gpu=args.gpu):
        print(line, flush=True)
    return 0
