"""The command line's parser. ``simulate``'s model, sensor and stream flags are generated
from :mod:`meshladar.forward.options` (the table :func:`meshladar.simulate` reads); the other
commands' few flags are written here."""

from __future__ import annotations

import argparse

from .. import __version__
from ..forward.options import MODELS, OPTIONS, SENSOR_OPTIONS
from ..reconstruct import FILTERS
from .argtypes import (KIND_TYPES, MergeCoatings, angle_list, bounce_count, bounces,
                       coatings, elevation_deg, nonnegative_float, nonnegative_int, pair,
                       positive_float, positive_int, unit_fraction, window_size)
from .argv import Parser
from .helptext import description
from .scan import BEAM_DEFAULTS

__all__ = ["build_parser"]

_RAW = argparse.RawDescriptionHelpFormatter
_EPILOG = ("examples:\n  meshladar demo\n  meshladar demo --angles-deg 0,2,4\n"
           "  meshladar materials\n  meshladar materials my_coatings.toml\n"
           "  meshladar paper paper-figures/\n"
           "  meshladar simulate disk_pair -o pair.npz --coating small=aluminum\n"
           "  meshladar reconstruct pair.npz -o pair.png\n"
           "  meshladar view disk_pair --view-angle 0 --screenshot view.png\n"
           "  meshladar study faceting study/\n  meshladar bench")
_SIMULATE_EPILOG = (
    "examples:\n  meshladar simulate disk_pair -o pair.npz --coating small=aluminum\n"
    "  meshladar simulate part.stl --material aluminum --views 90 -o part.npz\n"
    "  meshladar simulate part.stl --view-vectors 200 --normals smooth -o part3d.npz\n"
    "  meshladar simulate part.stl --mode slice --z0 0.1 -o slice.npz\n"
    "  meshladar simulate disk_pair --model mesh --tol 1e-2 -o mesh.npz\n\n"
    "Range r = -p.w is zero on the plane through the origin facing the ladar and grows "
    "away from it. A mesh is a 3-D target: the whole of it returns (values are areas x "
    "1/sr); --mode slice gives one slice per unit height.")
_RECEIVE_EPILOG = (
    "examples:\n  meshladar simulate part.stl -o part.npz --model mesh --radiometry power "
    "--standoff 1000 --beam-waist 0.05 --beam-divergence 1e-4 --pulse-energy 1e-3 "
    "--aperture 0.1\n  meshladar receive part.npz -o part-waves.npz --sample-rate 2e9 "
    "--pulse-fwhm 1e-9 --realisations 100 --speckle-cells 1 --seed 0 --plot "
    "part-waves.png")


def _add_option(group, o):
    """One :class:`meshladar.forward.options.Option` as a flag of ``group``."""
    if o.kind == "flag":
        group.add_argument(o.cli_flag, dest=o.name, action="store_true", help=o.help_text)
    elif o.kind == "choice":
        group.add_argument(o.cli_flag, dest=o.name, choices=o.choices, default=None,
                           help=o.help_text)
    else:
        group.add_argument(o.cli_flag, dest=o.name, type=KIND_TYPES[o.kind], default=None,
                           metavar=o.metavar, help=o.help_text)


def _scene_args(q):
    q.add_argument("scene", help="a packaged phantom's name (disk, ellipse, disk_pair), a "
                                 "phantom spec (.toml) or any mesh file trimesh reads "
                                 "(STL, OBJ, PLY, OFF, GLB/GLTF, 3MF, DAE, zip...)")
    q.add_argument("--material", default=None,
                   help="coating of a mesh's parts (default: dark_gray); a phantom's "
                        "shapes take --coating")
    q.add_argument("--coating", type=coatings, default=None, metavar="PART=NAME,...",
                   action=MergeCoatings,
                   help="coating per phantom shape or mesh part, e.g. small=aluminum "
                        "(default: each shape's own, or --material)")
    q.add_argument("--materials", default=None, metavar="TABLE.toml",
                   help="your own coating table: its names can be used by --material "
                        "and --coating (default: only the packaged coatings)")
    q.add_argument("--quiet", action="store_true",
                   help="no progress bar or summary (default: shown)")


def _sub(sub, name, commands, help, epilog):
    return sub.add_parser(name, help=help, description=description(commands[name]),
                          epilog=epilog, formatter_class=_RAW)


def _simple(sub, commands):
    d = _sub(sub, "demo", commands, "print the paper's coatings' monostatic BRDF",
             "example:\n  meshladar demo --angles-deg 0,1,5,45,90")
    d.add_argument("--angles-deg", type=angle_list,
                   default=[0.0, 1.0, 5.0, 10.0, 30.0, 60.0, 85.0, 90.0],
                   help="incidence angles in degrees, comma-separated (default: %(default)s)")
    m = _sub(sub, "materials", commands, "list a coating table",
             "examples:\n  meshladar materials\n  meshladar materials mine.toml")
    m.add_argument("table", nargs="?", default=None,
                   help="a TOML material table (default: the packaged paper coatings)")
    pp = _sub(sub, "paper", commands, "reproduce the paper's Figs 5-11 into a folder",
              "example:\n  meshladar paper paper-figures/")
    pp.add_argument("outdir", help="folder for the PNGs and paper_result.npz")
    pp.add_argument("--size", type=positive_int, default=512,
                    help="reconstruction size in pixels, at least 475, where the findings "
                         "hold (default: %(default)s)")


def _simulate(sub, commands):
    sim = _sub(sub, "simulate", commands, "simulate range profiles and save them",
               _SIMULATE_EPILOG)
    _scene_args(sim)
    sim.add_argument("-o", "--output", required=True, help="result file (.npz)")
    sim.add_argument("--model", choices=MODELS, default=None,
                     help="forward model (default: analytic for phantoms, mesh for meshes)")
    sens = sim.add_argument_group(
        "sensor (mesh model; SI units: metres, seconds, joules)",
        "a ladar at a finite standoff (perspective rays, ranges R - D from the origin), its "
        "beam, the atmosphere and the link budget: with --pulse-energy, --aperture and "
        "--standoff, received power (--radiometry power) is counted in photoelectrons per "
        "bin")
    for o in SENSOR_OPTIONS:
        _add_option(sens, o)
    sim.add_argument("--views", type=positive_int, default=None,
                     help="number of views evenly over 360 degrees about z (default: the "
                          "phantom's, or 360)")
    sim.add_argument("--angles-deg", type=angle_list, default=None,
                     help="view angles about z in degrees, comma-separated (default: "
                          "from --views)")
    sim.add_argument("--view-vectors", type=positive_int, default=None, metavar="N",
                     help="N view directions spread evenly over the sphere (mesh model) "
                          "(default: views about z)")
    sim.add_argument("--bins", type=positive_int, default=None,
                     help="number of range bins (default: the phantom's, or 512 covering "
                          "the ranges the target spans over the views)")
    sim.add_argument("--bin-width", type=positive_float, default=None,
                     help="range bin width in scene units (default: from --bins)")
    sim.add_argument("--segments", type=positive_int, default=None,
                     help="tessellation of an analytic phantom for --model mesh (default: "
                          "1024)")
    for o in OPTIONS:
        if o.cli:
            _add_option(sim, o)
    sim.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="run on an existing Dask cluster (tcp://host:8786) "
                          "(default: local)")
    sim.add_argument("--workers", type=positive_int, default=None,
                     help="run on a local Dask cluster of N processes "
                          "(default: no Dask)")


def _reconstruct(sub, commands):
    rec = _sub(sub, "reconstruct", commands,
               "invert a saved sinogram (FBP about z, or 3-D over the sphere) into a "
               "figure (PNG, PDF, SVG, JPEG, TIFF) and its values (.npz)",
               "examples:\n  meshladar reconstruct pair.npz -o pair.png\n"
               "  meshladar reconstruct pair.npz -o pair-log.png --log")
    rec.add_argument("result", help="a result file written by meshladar simulate")
    rec.add_argument("-o", "--output", required=True,
                     help="figure file: .png, .pdf, .svg, .jpg or .tif (the image's values go "
                          "to OUTPUT.image.npz beside it); or .npz: the values alone, no "
                          "figure (no matplotlib needed)")
    rec.add_argument("--size", type=positive_int, default=None,
                     help="image size in pixels, or voxels per side for 3-D views (default: "
                          "512, 128 in 3-D)")
    rec.add_argument("--smooth", type=nonnegative_float, default=None, metavar="BINS",
                     help="3-D views: Gaussian smoothing of each profile before the inversion "
                          "(default: 0)")
    rec.add_argument("--extent", type=positive_float, default=None,
                     help="half-width of the image (default: the bins' reach)")
    rec.add_argument("--center", type=pair, default=None, metavar="X,Y",
                     help="centre of the image (views about z; default: 0,0, the axis "
                          "the views turn about)")
    rec.add_argument("--filter", choices=FILTERS, default=None,
                     help="FBP filter (default: ramp)")
    rec.add_argument("--log", action="store_true",
                     help="log of the radiance (Fig. 11a) (default: off)")
    rec.add_argument("--clip", type=unit_fraction, default=None,
                     help="clip at this fraction of the maximum (Fig. 11b: 0.008) (default: "
                          "off)")
    rec.add_argument("--quiet", action="store_true", help="no summary line (default: shown)")


#: receive's flags: (flag, type, metavar, help); every default is None.
_RECEIVE_FLAGS = (
    ("--pulse-fwhm", positive_float, "S", "Gaussian transmitted pulse, full width at half "
     "maximum (default: a Dirac pulse)"),
    ("--pulse-samples", None, "FILE", "the pulse's own shape: a text file of power samples "
     "(commas, spaces or newlines), with --pulse-interval (default: none)"),
    ("--pulse-interval", positive_float, "S", "seconds between --pulse-samples (default: "
     "none)"),
    ("--response-fwhm", positive_float, "S", "Gaussian receiver impulse response (default: "
     "ideal)"),
    ("--standoff", nonnegative_float, "M", "time origin t = 2(r + D)/c (default: the "
     "simulation's sensor's, else 0)"),
    ("--scale", positive_float, "PE_PER_UNIT", "photoelectrons per unit of the sinogram, "
     "when it was not simulated with --pulse-energy and --aperture (default: none)"),
    ("--realisations", positive_int, "N", "draw N noise realisations (default: none)"),
    ("--seed", nonnegative_int, None, "seed of the noise (default: fresh entropy)"),
    ("--speckle-cells", positive_float, "M", "speckle cells per resolution cell, >= 1 "
     "(default: no speckle)"),
    ("--background-rate", nonnegative_float, "PER_S", "background photoelectrons per second "
     "(default: 0)"),
    ("--dark-rate", nonnegative_float, "PER_S", "dark counts per second (default: 0)"),
    ("--excess-noise", positive_float, "F", "APD excess noise factor, >= 1 (default: 1)"),
    ("--gain", positive_float, None, "APD mean gain (default: 1)"),
    ("--bits", positive_int, None, "digitiser bits, with --full-scale (default: no "
     "quantisation)"),
    ("--full-scale", positive_float, None, "digitiser full scale in output units, with "
     "--bits (default: none)"),
    ("--plot", None, "PNG", "a figure of a few views' waveforms with their noise band "
     "(default: none)"),
)


def _receive(sub, commands):
    rc = _sub(sub, "receive", commands, "waveforms (and noise) from a saved sinogram",
              _RECEIVE_EPILOG)
    rc.add_argument("result", help="a sinogram written by meshladar simulate")
    rc.add_argument("-o", "--output", required=True, help="waveforms file (.npz)")
    rc.add_argument("--sample-rate", type=positive_float, required=True, metavar="HZ",
                    help="digitiser rate, samples per second")
    rc.add_argument("--oversample", type=positive_int, default=8,
                    help="fine cells per sample for the convolutions (default: %(default)s)")
    for flag, kind, metavar, text in _RECEIVE_FLAGS:
        rc.add_argument(flag, type=kind, default=None, metavar=metavar, help=text)
    rc.add_argument("--quiet", action="store_true", help="no summary line (default: shown)")


def _view(sub, commands):
    vw = _sub(sub, "view", commands, "3-D view of a scene coloured by its return",
              "examples:\n  meshladar view disk_pair --view-angle 0 --screenshot pair.png\n"
              "  meshladar view part.glb --material aluminum\n"
              "  meshladar view room.stl --points room.las --color-by range_error\n"
              "  meshladar view bracket.glb --bounces 3 --screenshot bounces.png")
    _scene_args(vw)
    vw.add_argument("--view-angle", type=KIND_TYPES["finite_float"], default=None,
                    help="view angle about z in degrees (not with --points) (default: 90)")
    vw.add_argument("--screenshot", default=None,
                    help="render off screen into this PNG (default: open a window)")
    vw.add_argument("--log", action="store_true",
                    help="colour by log10 of the return (the scene alone: not with --points "
                         "or --bounces) (default: linear)")
    vw.add_argument("--size", type=window_size, default=(900, 700), metavar="WxH",
                    help="window or screenshot size in pixels (default: 900x700)")
    vw.add_argument("--points", default=None, metavar="FILE",
                    help="a point cloud written by meshladar scan (.las, .laz, .h5, .npz), drawn "
                         "over the scene (default: the scene coloured by its return)")
    vw.add_argument("--color-by", default=None,
                    choices=("intensity", "range", "return_number", "range_error", "doppler",
                             "channel", "scan_angle", "emission_time"),
                    help="the points' colour, with --points only (default: intensity)")
    vw.add_argument("--bounces", type=bounce_count, default=None, metavar="N",
                    help="colour faces by the order of bounces (1 to N, at most 8) that "
                         "dominates their return and draw sampled paths (a mesh; default: "
                         "the single bounce's return; not with --points)")
    vw.add_argument("--camera", choices=("oblique", "view"), default=None,
                    help="oblique: beside and above the ladar; view: along the beam from "
                         "the ladar (not with --points) (default: oblique)")


def _study(sub, commands):
    st = _sub(sub, "study", commands,
              "run a study (faceting, tomography3d or reconstruction) into a folder",
              "examples:\n  meshladar study faceting study/\n"
              "  meshladar study faceting study-full/ --full\n\nFinished study points are "
              "kept in OUTDIR/run: re-running the same command resumes an interrupted "
              "study.")
    st.add_argument("kind", choices=["faceting", "tomography3d", "reconstruction"],
                    help="which study: faceting (forward models against the analytic one), "
                         "tomography3d (the paper's findings in 3-D) or reconstruction "
                         "(FBP and iterative methods against view spacing)")
    st.add_argument("outdir", help="folder for faceting.csv/json, results and figures")
    st.add_argument("--full", dest="setting", action="store_const", const="full",
                    default="quick", help="the full sweep (faceting: 360 views, segments to "
                                          "4096; tomography3d: 2000 views, 128^3) (default: "
                                          "the quick one)")
    st.add_argument("--photons", type=positive_float, default=None,
                    help="reconstruction study: photon-counting noise with this many "
                         "photoelectrons in each sinogram's brightest bin (default: none)")
    st.add_argument("--speckle", type=positive_float, default=None, metavar="M",
                    help="reconstruction study, with --photons: speckle of M >= 1 cells per "
                         "bin (1: fully developed) (default: none)")
    st.add_argument("--background", type=positive_float, default=None, metavar="B",
                    help="reconstruction study, with --photons: B background "
                         "photoelectrons per bin, its mean subtracted (default: none)")
    st.add_argument("--quiet", action="store_true", help="no progress bar (default: shown)")
    bch = _sub(sub, "bench", commands, "time the forward models (median of several runs)",
               "example:\n  meshladar bench --repeats 7")
    bch.add_argument("--repeats", type=positive_int, default=5,
                     help="timed runs per case after one warm-up (default: %(default)s)")
    bch.add_argument("--full", action="store_true",
                     help="also the streaming run: 360 views x 1e6 rays (about a minute) "
                          "(default: off)")
    bch.add_argument("--gpu", action="store_true",
                     help="only the GPU line: Warp's first hits against the packet "
                          "backend's on the same rays, on a CUDA device where there is one "
                          "(needs meshladar[gpu]) (default: off)")


_SCAN_EPILOG = """examples:
  meshladar scan part.glb --pattern "rotating elevations_deg=-15:15:32 rotation_hz=10 \\
      pulse_rate=3e5 duration=0.1" --platform "moving position=-20,0,1.5 velocity=10,0,0" \\
      -o points.las
  meshladar scan part.glb --pattern "flash rows=64 columns=64 ifov_deg=0.05" \\
      --platform "static position=-100,0,0" --tol 0.05 -o frame.h5 --waveforms w.h5
  meshladar scan terrain.ply --pattern "oscillating half_angle_deg=20 scan_hz=50 \\
      pulse_rate=1e5 duration=1" --platform flight.csv -o strip.laz
  meshladar scan terrain.ply --pattern "oscillating half_angle_deg=20 scan_hz=50 \\
      pulse_rate=1e5 duration=1" --platform "gps_week.csv time_offset=345000 \\
      boresight_deg=0,0,0.5" -o strip.laz
  meshladar scan terrain.ply --pattern "oscillating half_angle_deg=20 scan_hz=50 \\
      pulse_rate=1e4 duration=0.1" --platform "waypoints times=0,0.05,0.1 \\
      positions=0,0,300,3,0,300,6,0,300 attitudes_deg=0,90,0,0,90,0,0,90,0 \\
      interpolation=spline mount_offset=0,0,-0.5" -o strip.las"""

#: scan's sensor flags: (flag, type, default, metavar, help).
_SCAN_FLAGS = (
    ("--pulse-energy", positive_float, 1e-6, "J", "energy per pulse"),
    ("--aperture", positive_float, 0.05, "M", "receiver aperture diameter"),
    ("--sample-rate", positive_float, 2e9, "HZ", "digitiser samples per second"),
    ("--pulse-fwhm", positive_float, 5e-9, "S", "the pulse's full width at half maximum"),
    ("--divergence", nonnegative_float, BEAM_DEFAULTS["divergence"], "RAD",
     "the beam's 1/e2 half-angle (not with a flash pattern)"),
    ("--tol", positive_float, BEAM_DEFAULTS["tol"], "FRACTION", "largest error in a "
     "pulse's energy share beyond an edge: sets the sub-rays per pulse (a flash pattern: "
     "m x m sub-rays a pixel, m = ceil(1/(2 tol)))"),
    ("--sub-rays", positive_int, None, "N", "fixed sub-rays per pulse instead of --tol "
     "(not with a flash pattern)"),
    ("--background-rate", nonnegative_float, 0.0, "PER_S", "background photoelectrons per s"),
    ("--dark-rate", nonnegative_float, 0.0, "PER_S", "dark counts per second"),
    ("--max-returns", positive_int, 5, "N", "most returns per pulse (1-15)"),
    ("--geiger-shots", positive_int, None, "K", "Geiger-mode pixels: K shots histogrammed "
     "per pulse, Coates-corrected"),
    ("--dead-time", positive_float, "inf (once per shot)", "S", "Geiger-mode pixels: "
     "seconds blind after firing (with --geiger-shots)"),
    ("--detection-efficiency", unit_fraction, 1.0, "P", "Geiger-mode pixels: the "
     "probability that a photoelectron fires (with --geiger-shots)"),
    ("--false-alarm", positive_float, 1e-6, "P", "the detector's largest probability that "
     "a noise-only sample crosses its threshold, (0, 0.5]"),
    ("--seed", nonnegative_int, 0, "N", "the noise's seed"),
)


#: scan's flags left None when not given (what applies depends on whether they were).
_GIVEN_ONLY = ("--dead-time", "--detection-efficiency", "--false-alarm")


def _scan(sub, commands):
    sc = _sub(sub, "scan", commands, "a scanner's point cloud of a scene (LAS, HDF5, NPZ)",
              _SCAN_EPILOG)
    _scene_args(sc)
    sc.add_argument("--pattern", required=True, metavar="'KIND key=value ...'",
                    help="raster, rotating, oscillating, risley or flash, with its "
                         "constructor's arguments")
    sc.add_argument("--platform", required=True, metavar="'KIND key=value ...'|FILE.csv",
                    help="static, moving or waypoints with their arguments (each key "
                         "once; any platform's mount_offset and boresight_deg; a waypoints' "
                         "positions and attitudes_deg flat, three values a waypoint), or "
                         "a trajectory file (time,x,y,z,roll,pitch,yaw), optionally "
                         "followed by interpolation=, time_offset= (the file's time at "
                         "the pattern's t = 0), mount_offset=, boresight_deg=")
    sc.add_argument("-o", "--output", required=True,
                    help="points file (.las, .laz, .h5; .npz needs numpy alone)")
    sc.add_argument("--waveforms", default=None, metavar="FILE.h5",
                    help="also write every pulse's waveform to HDF5 (default: not written)")
    sc.add_argument("--run-dir", default=None, metavar="DIR",
                    help="resumable run folder: finished chunks are kept there, and the "
                         "same command run again computes only the rest, to the same "
                         "points (not with --waveforms; default: none)")
    sc.add_argument("--profile", choices=("gaussian", "tophat"), default=None,
                    help="the beam's profile (not with a flash pattern) (default: "
                         f"{BEAM_DEFAULTS['profile']})")
    sc.add_argument("--noise", action="store_true",
                    help="shot noise even without background (default: expected waveforms)")
    sc.add_argument("--discrete", action="store_true",
                    help="discrete returns: no waveform, a pulse's sub-rays grouped in "
                         "range, expected values (default: waveforms and their returns)")
    sc.add_argument("--cfar", action="store_true",
                    help="threshold from each record's own background (default: from "
                         "--background-rate and --dark-rate)")
    for flag, kind, default, metavar, text in _SCAN_FLAGS:
        # the beam's and the Geiger array's defaults are applied by the command: whether a
        # flag was given decides what applies (a flash pattern refuses --divergence)
        later = flag.lstrip("-") in BEAM_DEFAULTS or flag in _GIVEN_ONLY
        sc.add_argument(flag, type=kind, default=None if later else default,
                        metavar=metavar, help=f"{text} (default: {default})")


_LRCS_EPILOG = """examples:
  meshladar lrcs part.stl --views 72 -o sigma.csv
  meshladar lrcs bracket.glb --view-vectors 200 --per-part
  meshladar lrcs disk_pair --angles-deg 0,45,90"""


def _lrcs(sub, commands):
    lr = _sub(sub, "lrcs", commands, "laser radar cross sections per view (and part)",
              _LRCS_EPILOG)
    _scene_args(lr)
    lr.add_argument("-o", "--output", default=None,
                    help="also write the table to this CSV file (default: printed only)")
    lr.add_argument("--views", type=positive_int, default=None,
                    help="views evenly over 360 degrees about z (default: 36)")
    lr.add_argument("--angles-deg", type=angle_list, default=None,
                    help="view angles about z in degrees, comma-separated")
    lr.add_argument("--view-vectors", type=positive_int, default=None, metavar="N",
                    help="N view directions spread evenly over the sphere (meshes)")
    lr.add_argument("--elevation-deg", type=elevation_deg, default=None, metavar="E",
                    help="raise the views of --views or --angles-deg E degrees above the "
                         "x-y plane (meshes; the table gives each view's vector; "
                         "default: 0)")
    lr.add_argument("--bounces", type=bounces, default=1,
                    help="orders of bounces, 1-8 or auto (meshes; default: %(default)s)")
    lr.add_argument("--bounce-samples", type=positive_int, default=None, metavar="N",
                    help="sampled paths per view and order beyond the first (the "
                         "sigma_stderr column falls as 1/sqrt(N); default: 32768)")
    lr.add_argument("--per-part", action="store_true",
                    help="each part's cross section too (its single bounce and the paths "
                         "leaving from it; default: off)")
    lr.add_argument("--ray-spacing", type=positive_float, default=None,
                    help="distance between rays, scene units (default: the model's)")
    lr.add_argument("--normals", choices=("flat", "smooth"), default=None,
                    help="a mesh's shading normals (default: flat)")
    lr.add_argument("--seed", type=nonnegative_int, default=None,
                    help="seed of the sampling (default: 0)")


def build_parser(commands) -> argparse.ArgumentParser:
    """The parser of every command; ``commands`` maps each command's name to its function
    (its docstring is the command's description).

    Parameters
    ----------
    commands : dict of str to callable
        Every command's function by name: ``demo``, ``materials``, ``paper``,
        ``simulate``, ``reconstruct``, ``receive``, ``scan``, ``lrcs``, ``view``, ``study``
        and ``bench``
        (:data:`meshladar.cli.COMMANDS`). Only their docstrings are read here; the
        functions are not called.

    Returns
    -------
    argparse.ArgumentParser
        The ``meshladar`` parser: ``--version`` and one required subcommand, stored as
        ``command``, each with its flags (``simulate``'s model and sensor flags from
        :mod:`meshladar.forward.options`) and examples in its epilog.

    Raises
    ------
    KeyError
        When ``commands`` lacks one of the command names.
    """
    p = Parser(
        prog="meshladar", description="Mesh-based ladar simulation and reflection tomography.",
        epilog=_EPILOG, formatter_class=_RAW)
    p.add_argument("--version", action="version", version=f"meshladar {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (_simple, _simulate, _reconstruct, _receive, _scan, _lrcs, _view, _study):
        add(sub, commands)
    return p
