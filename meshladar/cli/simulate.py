"""``meshladar simulate``: a scene's range profiles, saved with the scene and parameters.

The model options' flags, checks and "does not apply" errors come from
:mod:`meshladar.forward.options`, the table :func:`meshladar.simulate` reads too."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np

from .. import io
from ..errors import MeshladarWarning, ParameterError
from ..forward import simulate
from ..ladar import MAX_VIEWS, Ladar
from ..meshes import fibonacci_sphere
from ..forward.job import QUICK_RAYS
from ..forward.options import OPTIONS, SENSOR_OPTIONS
from ..raytrace.backends import backend
from ..raytrace.plan import plan_trace
from ..sensor import FloodBeam, GaussianBeam, Sensor
from ..stream import dask_executor
from .checks import check_outdir, check_output
from .sources import load_source
from .words import flag_words

__all__ = ["cmd_simulate", "load_scene", "quick_backend", "SCENE_LABELS"]

#: What the command line calls load_source()'s arguments, in its errors.
SCENE_LABELS = {"source": "SCENE", "material": "--material", "coatings": "--coating"}
_BEAM = ("flood_radius", "beam_waist", "beam_divergence", "beam_offset")


def load_scene(args):
    """(scene, default ladar or None, default model) from SCENE: phantom, spec or mesh
    (:func:`meshladar.cli.sources.load_source`).

    Parameters
    ----------
    args : argparse.Namespace
        ``scene``: a packaged phantom's name, a phantom spec (``.toml``) or a mesh file;
        ``material``: a mesh's coating name, or None; ``coating``: ``{part or shape name:
        coating name}``, or None; ``materials``: the path of a TOML coating table whose
        names join the packaged ones, or None.

    Returns
    -------
    tuple
        ``(Scene, Ladar or None, str)``: the scene, a phantom's own ladar set-up (None for
        a mesh), and its default model (``"analytic"`` for a phantom, ``"mesh"`` for a
        mesh).

    Raises
    ------
    ParameterError
        As :func:`meshladar.cli.sources.load_source`, its messages naming the flags
        (``SCENE``, ``--material``, ``--coating``): an unknown coating, no such mesh file
        or phantom, ``--material`` given for a phantom.
    PhantomSpecError
        For a phantom spec that is not valid.
    GeometryError
        For a mesh file that is not a triangle mesh.
    """
    return load_source(args.scene, material=args.material, coatings=args.coating,
                            materials_file=args.materials, labels=SCENE_LABELS)


def _ladar(args, scene, default):
    for flag, n in (("--views", args.views), ("--view-vectors", args.view_vectors)):
        if n is not None and n > MAX_VIEWS:
            raise ParameterError(f"{flag}: at most {MAX_VIEWS:.0e} views; got {n}")
    vectors = None if args.view_vectors is None else fibonacci_sphere(args.view_vectors)
    angles = args.angles_deg if args.angles_deg is not None else (
        np.arange(args.views) * (360.0 / args.views) if args.views else None)
    if args.bins or args.bin_width:
        ladar = Ladar.covering(scene, n_bins=args.bins, bin_width=args.bin_width,
                               angles_deg=angles, view_vectors=vectors)
        if args.bins and args.bin_width:
            _warn_uncovered(scene, ladar)
        return ladar
    if default is not None and vectors is None:
        return default if angles is None else Ladar(angles, default.bin_edges)
    return Ladar.covering(scene, n_bins=512, angles_deg=angles, view_vectors=vectors)


def _warn_uncovered(scene, ladar):
    """``--bins N --bin-width W`` fix the bins' reach (N W about the target's middle): warn,
    with the numbers and the fix, when it does not cover the ranges the target spans over
    the views (their returns would be cut off without a word)."""
    lo, hi = scene.range_span(ladar.view_vectors)
    first, last = float(ladar.bin_edges[0]), float(ladar.bin_edges[-1])
    if lo >= first and hi <= last:
        return
    width = (last - first) / ladar.n_bins
    middle = 0.5 * (first + last)
    need = math.ceil(2.0 * max(hi - middle, middle - lo) / width - 1e-9)
    warnings.warn(f"--bins {ladar.n_bins} x --bin-width {width:g} cover ranges "
                  f"[{first:.6g}, {last:.6g}], but the target spans [{lo:.6g}, {hi:.6g}] "
                  "over these views: returns beyond the bins are lost; give --bins "
                  f"{need} (or only one of --bins and --bin-width: the bins then cover the "
                  "target)", MeshladarWarning, stacklevel=2)


def _sensor(args):
    """The Sensor the sensor flags describe, or None when none is given."""
    if all(getattr(args, o.name) is None for o in SENSOR_OPTIONS):
        return None
    gaussian = [o.cli_flag for o in SENSOR_OPTIONS if o.name in _BEAM[1:]
                and getattr(args, o.name) is not None]
    if gaussian and args.beam_waist is None:
        raise ParameterError(f"{gaussian[0]} shapes a Gaussian beam: give --beam-waist too")
    if gaussian and args.flood_radius is not None:
        raise ParameterError("--flood-radius and --beam-waist both choose the beam; give one")
    if args.beam_waist is not None:
        beam = GaussianBeam(args.beam_waist, divergence=args.beam_divergence or 0.0,
                            offset=args.beam_offset or (0.0, 0.0))
    else:
        beam = FloodBeam(args.flood_radius)
    kw = {o.name: getattr(args, o.name) for o in SENSOR_OPTIONS
          if o.name not in _BEAM and getattr(args, o.name) is not None}
    return Sensor(beam=beam, **kw)     # its refusals in the flags' words: main's in_flags


#: What the API calls the values simulate's own flags set (the ladar's, the model).
_API_FLAGS = {"n_bins": "--bins", "bin_width": "--bin-width", "angles_deg": "--angles-deg",
              "view_vectors": "--view-vectors", "model": "--model"}
#: Every API name with its flag: the options', the sensor fields', the ladar's.
_FLAGS = {**{o.name: o.cli_flag for o in OPTIONS + SENSOR_OPTIONS if o.cli}, **_API_FLAGS}
#: Names a message uses only for their values: an underscore in them, ``tol``, or a sensor
#: field's (the sensor's messages say "standoff" and "wavelength" for its flags').
_UNIQUE = [n for n in _FLAGS if "_" in n or n == "tol" or n in {o.name for o in SENSOR_OPTIONS}]
#: The beam classes' words and the flags that make them; the API's advice that has no one
#: flag (a switch to leave out, the sensor the standoff makes).
_PHRASES = (("FloodBeam(radius=...)", "--flood-radius"), ("a GaussianBeam", "--beam-waist"),
            ("sensor.beam=FloodBeam(radius=None)", "no --flood-radius"),
            ("use no --footprint", "leave out --footprint"),
            ("drop receiver or sensor", "drop --receiver or --standoff"))
_WORDS = flag_words(_FLAGS, _UNIQUE, _PHRASES)


def in_flags(message):
    """An API message in the command line's words (:func:`.words.flag_words`):
    ``mode='3d'`` becomes ``--mode 3d`` for every option; a name messages use only for its
    value (``ray_spacing``, ``n_bins``, ``tol``, a Sensor field's) becomes its flag
    wherever it stands outside quotes and paths (``/data/n_bins/part.stl`` is kept); any
    other option's name (``jobs``) where the message begins with it as a rule's subject.

    Parameters
    ----------
    message : str
        An error's or a warning's text from the API.

    Returns
    -------
    str
        The text with the API's names as simulate's flags.
    """
    return re.sub(r"^(workers|scheduler):", r"--\1:", _WORDS(message))


def _given(args, attr):
    v = getattr(args, attr, None)
    return v is not None and v is not False


def check_applicable(args, model, is_phantom):
    """Options that do not apply to this run are errors, never silently ignored: which
    model takes which option is the options table's."""
    exclusive = [("--views", "views"), ("--angles-deg", "angles_deg"),
                 ("--view-vectors", "view_vectors")]
    named = [flag for flag, attr in exclusive if _given(args, attr)]
    if len(named) > 1:
        raise ParameterError(f"{named[0]} and {named[1]} both choose the views; give one")
    for o in OPTIONS + SENSOR_OPTIONS:
        if o.cli and model not in o.models and _given(args, o.name):
            owner = " or ".join(o.models)
            raise ParameterError(f"{o.cli_flag} is an option of the {owner} model; the "
                                 f"{model} model does not use it (add --model "
                                 f"{o.models[0]})")
    if _given(args, "segments") and not (is_phantom and model == "mesh"):
        raise ParameterError("--segments tessellates an analytic phantom for --model mesh; "
                             "it does not apply here")
    if _given(args, "z0") and args.mode != "slice" and not (is_phantom and args.mode is None):
        raise ParameterError("--z0 places the slice plane: it needs --mode slice")
    if _given(args, "seed") and args.sampling == "regular":
        raise ParameterError("--seed jitters the rays: it needs --sampling stratified, not "
                             "regular")
    if _given(args, "max_rays") and not _given(args, "tol"):
        raise ParameterError("--max-rays bounds the work of --tol; give --tol too")
    if _given(args, "ray_spacing") and _given(args, "rays_per_bin"):
        raise ParameterError("--ray-spacing and --rays-per-bin both set how dense the rays "
                             "are; give one")
    if _given(args, "bounce_samples") and args.bounces in (None, 1):
        raise ParameterError("--bounce-samples samples the paths beyond the first bounce: "
                             "it needs --bounces 2 or more (or auto)")
    if _given(args, "jobs") and (_given(args, "scheduler") or _given(args, "workers")):
        raise ParameterError("--jobs runs local processes; with --scheduler or --workers "
                             "Dask runs the work: give one")


def _check_model_fits(args, model, scene):
    """What the API refuses in its own words (``model='mesh'``), said in flags: a 2-D model
    needs a phantom's analytic shapes and views about z."""
    if model == "mesh":
        return
    if not scene.shapes:
        raise ParameterError(f"--model {model} needs a phantom (analytic disks and "
                             f"ellipses); {args.scene!r} is a mesh: use --model mesh")
    if args.view_vectors is not None:
        raise ParameterError(f"--view-vectors places views over the sphere, which only "
                             f"--model mesh traces; the {model} model takes views about z "
                             "(--views or --angles-deg)")


def _summary(args, sino, ladar, model):
    """One line: what was simulated, how (mode, normals, sampling, rays, bins) and where."""
    info = sino.info
    how = f"{model} model"
    if model == "mesh":
        rec = info.get("receiver")
        how += (f", {info.get('mode')} mode, {info.get('normals')} normals, "
                f"{info.get('sampling')} sampling, ray spacing {info.get('ray_spacing'):.4g}, "
                f"{'footprint' if info.get('footprint') else 'point'} bins, "
                + ("monostatic" if rec is None else "bistatic receiver") + ", "
                f"{info.get('rays', 0):,} rays cast ({info.get('backend')} backend)")
        if info.get("mode") == "slice":
            how += f" (values per unit height at z0 = {info.get('z0'):g})"
        if "error_estimate" in info:
            how += f", estimated error {info['error_estimate']:.2g}"
    return (f"{args.scene}: {how}; {ladar.n_views} views x {ladar.n_bins} bins over range "
            f"[{ladar.bin_edges[0]:.6g}, {ladar.bin_edges[-1]:.6g}] (range 0 on the plane "
            f"through the origin facing the ladar); {sino.radiometry or 'paper'} "
            f"radiometry; mean total return per view {sino.total().mean():.6g}; wrote "
            f"{args.output}")


def _model_options(args, model):
    """simulate's options from the flags: every table option of ``model`` that was given."""
    opts = {o.name: getattr(args, o.name) for o in OPTIONS
            if o.cli and model in o.models and o.group == "model" and _given(args, o.name)}
    if model == "mesh":
        sensor = _sensor(args)
        if sensor is not None:
            opts["sensor"] = sensor
    opts["jobs"] = args.jobs                 # the stream's options: every model takes them
    if args.run_dir is not None:
        opts["run_dir"] = args.run_dir
    opts["progress"] = not args.quiet
    return opts


#: plan_trace's options among simulate's.
_PLAN_OPTIONS = ("mode", "normals", "back_faces", "z0", "ray_spacing", "rays_per_bin",
                 "sampling", "seed", "receiver", "sensor")


def quick_backend(scene, ladar, model, opts):
    """The backend ``auto`` stands for on the command line: embreex for a mesh run of at
    most :data:`meshladar.forward.job.QUICK_RAYS` rays (its plan's estimate), which is then
    cast one ray at a time and weighed in numpy, calling none of numba's compiled loops:
    a command does not load them (0.2-0.3 s) or compile them (2-3 s, on its first run
    after an install). Otherwise (a bigger run, another model, a backend
    named, ``--tol``, ``--bounces``, no embreex here), ``opts`` as they are.

    Parameters
    ----------
    scene : meshladar.Scene
        The run's scene (a mesh, or a phantom tessellated for the mesh model).
    ladar : meshladar.Ladar
        Its views and bins.
    model : str
        The model that runs; only ``"mesh"`` is concerned.
    opts : dict
        simulate's options from the flags (``backend`` among them where given).

    Returns
    -------
    dict
        ``opts``, with ``backend="embreex"`` where the run is that small.

    Raises
    ------
    ParameterError
        The plan's refusals (:func:`meshladar.raytrace.plan.plan_trace`), before any work.
    """
    if model != "mesh" or opts.get("backend", "auto") != "auto" or "tol" in opts \
            or opts.get("bounces", 1) != 1 or not backend("embreex").available()[0]:
        return opts
    with warnings.catch_warnings():        # the run's own plan gives them, once
        warnings.simplefilter("ignore")
        plan = plan_trace(scene, ladar, backend="embreex",
                          **{k: opts[k] for k in _PLAN_OPTIONS if k in opts})
    return {**opts, "backend": "embreex"} if plan.rays <= QUICK_RAYS else opts


def cmd_simulate(args) -> int:
    """Simulate a scene's range profiles and save them (sinogram, scene, parameters).

    The model is ``--model``, else the scene's default (analytic for a phantom, mesh for a
    mesh); an analytic phantom run with the mesh model and no ``--tol`` is tessellated into
    ``--segments`` (default 1024) segments first. The views and bins: ``--bins`` or
    ``--bin-width`` give bins covering the scene (:meth:`meshladar.ladar.Ladar.covering`);
    otherwise a phantom keeps its own bins (and views, unless ``--views`` or
    ``--angles-deg`` replace them), and any other run gets 512 bins covering the scene.
    ``--views N`` spreads N views evenly over 360° about z. The sinogram, the scene and the
    run's parameters are saved with :func:`meshladar.io.save_sinogram`.

    Parameters
    ----------
    args : argparse.Namespace
        ``output``: the ``.npz`` path; the scene's options (see :func:`load_scene`);
        ``model``; ``views``, ``angles_deg``, ``view_vectors`` (at most one of them),
        ``bins``, ``bin_width``, ``segments``; every model, sensor and stream option of
        :mod:`meshladar.forward.options` that has a flag (None or False when not given);
        ``scheduler`` (a Dask scheduler address) or ``workers`` (a local Dask cluster of
        that many processes) to run on Dask; ``quiet``: no progress bar or summary line.

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        Before the work: when ``output`` is not a ``.npz`` path or names an input (the
        scene, the coating table or the run folder); when the scene cannot be loaded
        (:func:`load_scene`); when two of ``views``, ``angles_deg`` and ``view_vectors`` are
        given, or ``views`` or ``view_vectors`` is above 10⁶
        (``meshladar.ladar.MAX_VIEWS``); when an option does not apply to the model or the
        rest of the command (e.g. ``--z0`` without ``--mode slice``, ``--seed`` with regular
        sampling, ``--max-rays`` without ``--tol``, ``--jobs`` with Dask); when a 2-D model
        is given a mesh or ``--view-vectors``; when the sensor flags contradict one another.
        During the run: the API's own refusals, put in the flags' words.
    PhantomSpecError, GeometryError
        For a phantom spec or a mesh file that cannot be loaded (:func:`load_scene`).
    """
    check_output(args.output, (".npz",), [args.scene, args.materials, args.run_dir],
                 run_dir=args.run_dir)
    if args.run_dir is not None:
        check_outdir(args.run_dir, "--run-dir")
    scene, default_ladar, default_model = load_scene(args)
    model = args.model or default_model
    check_applicable(args, model, default_ladar is not None)
    _check_model_fits(args, model, scene)
    ladar = _ladar(args, scene, default_ladar)
    if model == "mesh" and not scene.is_mesh and args.tol is None:  # --tol tessellates
        scene = scene.tessellate(args.segments or 1024)
    opts = _model_options(args, model)
    # the API's refusals (the Dask cluster's own checks too) are put in the flags' words
    # by main (in_flags), for every error of this command
    opts = quick_backend(scene, ladar, model, opts)
    if args.scheduler or args.workers:
        with dask_executor(args.scheduler, workers=args.workers or 2) as ex:
            sino = simulate(scene, ladar, model=model, executor=ex,
                            **{k: v for k, v in opts.items() if k != "jobs"})
    else:
        sino = simulate(scene, ladar, model=model, **opts)
    params = {"scene": args.scene, "model": model,
              "options": {k: (v.describe() if k == "sensor" else v) for k, v in opts.items()
                          if k != "progress"},
              "n_views": ladar.n_views, "n_bins": ladar.n_bins}
    io.save_sinogram(args.output, sino, scene=scene, params=params)
    if not args.quiet:
        print(_summary(args, sino, ladar, model))
    return 0
