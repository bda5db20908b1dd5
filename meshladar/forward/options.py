"""The forward models' options, declared once.

Each option of :func:`meshladar.simulate` is one :class:`Option` record: its name, the kind
of value it takes, its default, its help, and which models take it. ``simulate`` refuses an
option its model does not take from this table; the command line's ``simulate`` parser is
generated from it (flags, types, choices, help, and the "does not apply to this model"
errors); the documentation lists it. A number or a rule written here is written nowhere
else (the habit of scikit-learn's and Mitsuba's parameter tables: a thread threshold once
read three different numbers in three places of this project; it is now
:data:`meshladar.stream.THREADS_FROM` alone).

>>> from meshladar.forward.options import option, options_of
>>> option("footprint").models
('mesh',)
>>> "pixel_size" in options_of("pixel")
True
"""

from __future__ import annotations

from dataclasses import dataclass

from ..raytrace.backends import BACKENDS
from ..raytrace.grid import MODES, SAMPLINGS
from ..raytrace.views import BACK_FACES, NORMALS
from ..sensor import RADIOMETRIES
from ..stream import THREADS_FROM

__all__ = ["Option", "MODELS", "OPTIONS", "SENSOR_OPTIONS", "option", "options_of"]

#: The forward models available in this version.
MODELS = ("analytic", "mesh", "pixel")

#: The kinds of value an option takes; the command line parses each with its own checker.
KINDS = ("choice", "flag", "positive_float", "nonnegative_float", "finite_float",
         "unit_fraction", "positive_int", "nonnegative_int", "direction", "pair", "object",
         "path", "bounces")


@dataclass(frozen=True)
class Option:
    """One option of :func:`meshladar.simulate`.

    Attributes
    ----------
    name : str
        The keyword ``simulate`` takes (the flag is ``--name-with-dashes`` unless ``flag``).
    kind : str
        One of :data:`KINDS`: how the command line parses it (``"object"``: API only).
    help : str
        One sentence for the user, without the default.
    default : str
        What happens when it is not given, in words (``"flat"``, ``"from --rays-per-bin"``).
    models : tuple of str
        The models that take it; any other model refuses it.
    choices : tuple of str
        The valid values of a ``"choice"``.
    metavar : str or None
        The command line's placeholder.
    group : str
        ``"model"``, ``"stream"`` (every model; :mod:`meshladar.stream`) or ``"sensor"``
        (fields of :class:`meshladar.sensor.Sensor` and its beam, in SI units).
    cli : bool
        Whether the command line offers it (an executor object or a Sensor is API only).
    flag : str or None
        The command line's flag where it is not ``--name-with-dashes`` (``cli_flag``).

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`KINDS`, ``choices`` are given without kind
        ``"choice"`` (or that kind without them), or ``models`` names a model outside
        :data:`MODELS`.
    """

    name: str
    kind: str
    help: str
    default: str
    models: tuple[str, ...] = MODELS
    choices: tuple[str, ...] = ()
    metavar: str | None = None
    group: str = "model"
    cli: bool = True
    flag: str | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}; got {self.kind!r}")
        if (self.kind == "choice") != bool(self.choices):
            raise ValueError(f"option {self.name!r}: choices go with kind 'choice'")
        unknown = set(self.models) - set(MODELS)
        if unknown:
            raise ValueError(f"option {self.name!r}: models must be among {MODELS}; got "
                             f"{sorted(unknown)}")

    @property
    def cli_flag(self) -> str:
        """The command line's flag."""
        return self.flag or "--" + self.name.replace("_", "-")

    @property
    def help_text(self) -> str:
        """The help with its default, as the command line and the docs print it."""
        return f"{self.help} (default: {self.default})"


_MESH = ("mesh",)

#: simulate's options, in the order the command line and the errors list them.
OPTIONS: tuple[Option, ...] = (
    Option("pixel_size", "positive_float", "pixel size for --model pixel", "a quarter bin",
           ("pixel",)),
    Option("ray_spacing", "positive_float", "distance between rays in scene units",
           "from --rays-per-bin (mesh), a quarter bin (pixel)", ("mesh", "pixel")),
    Option("radiometry", "choice", "paper: the paper's Eq. 8, ∫ F cos θ dA per bin; power: "
           "the power a receiver collects, ∫ F cos θi cos θr dA (every model)", "paper",
           choices=RADIOMETRIES),
    Option("mode", "choice", "mesh model: 3d (the whole target) or slice (one plane z = z0, "
           "per unit height)", "3d for meshes, slice for phantoms", _MESH, choices=MODES),
    Option("z0", "finite_float", "height of the slice plane for --mode slice",
           "the target's mid-height", _MESH),
    Option("normals", "choice", "mesh model shading normals",
           "flat; with --tol smooth for meshes, exact for phantoms", _MESH, choices=NORMALS),
    Option("back_faces", "choice", "faces seen from behind: two-sided (they return as if "
           "seen from the front) or ignore (they stop the ray and return nothing)",
           "two-sided", _MESH,
           choices=BACK_FACES),
    Option("rays_per_bin", "positive_float", "rays per range-bin width",
           "1 in 3d, at least 128 across the target; 8 in slice", _MESH),
    Option("backend", "choice", "mesh model ray casting: packets (coherent packets, Embree 4 "
           "from the embreex wheel), raster (packets, with a dense orthographic view's "
           "first hits drawn into a depth buffer where its normals are flat and its "
           "receiver at the ladar), embreex (one ray at a time, the reference), warp "
           "(NVIDIA Warp on a CUDA device; warp-cpu: its kernels on the CPU) or auto",
           "auto: warp on a CUDA device, else raster when the packets load; on the command "
           "line, embreex for a run of at most 2^20 rays (it starts without numba's "
           "compiled loops)", _MESH,
           choices=BACKENDS),
    Option("sampling", "choice", "rays at a seeded random offset in their cell (stratified: "
           "unbiased) or at cell centres", "stratified in 3d, regular in slice", _MESH,
           choices=SAMPLINGS),
    Option("seed", "nonnegative_int", "seed of the stratified sampling", "0", _MESH),
    Option("receiver", "direction", "bistatic receiver direction from the scene (one, or "
           "one per view in the API)", "collocated with the ladar", _MESH, metavar="X,Y,Z"),
    Option("footprint", "flag", "spread each ray over the range its footprint covers on "
           "the facet", "point binning", _MESH),
    Option("tol", "positive_float", "relative sinogram accuracy: meshladar picks rays and "
           "segments (meshladar.forward.refine)", "off", _MESH),
    Option("bounces", "bounces", "surface interactions per path: 1 (single bounce), up to "
           "8, or auto (the orders up to the highest at or above --tol, else 0.01, of the "
           "single bounce, of 8 sampled); a convex scene never samples a second bounce "
           "(meshladar.forward.bounces)", "1", _MESH),
    Option("bounce_samples", "positive_int", "sampled paths per view and order beyond the "
           "first", "32768", _MESH),
    Option("max_rays", "positive_float", "budget of rays for --tol over all its refinement "
           "runs", "2e9", _MESH),
    Option("sensor", "object", "a meshladar.sensor.Sensor: a ladar at a finite standoff, its "
           "beam, the atmosphere and the link budget (the sensor flags build one)",
           "at infinity, a flood, relative units", _MESH, cli=False),
    Option("jobs", "positive_int", "workers for chunks of views, any model: threads sharing "
           "one Embree scene (mesh), processes (analytic, pixel)",
           f"1; the mesh model splits a view's rows over the cores from {THREADS_FROM:.0e} "
           "rays", group="stream"),
    Option("executor", "object", "any concurrent.futures.Executor to run the chunks on "
           "(threads, processes, a Dask cluster's); overrides jobs", "jobs", group="stream",
           cli=False),
    Option("progress", "object", "a progress bar over the views, on a terminal only",
           "off (the command line: on, --quiet turns it off)", group="stream", cli=False),
    Option("run_dir", "path", "resumable run folder: finished chunks are kept there, and "
           "re-running the same job resumes", "none", group="stream"),
)

#: The command line's sensor flags: (option, Sensor or beam field). They apply to the mesh
#: model and build one :class:`meshladar.sensor.Sensor` (its ``sensor`` option).
SENSOR_OPTIONS: tuple[Option, ...] = tuple(
    Option(name, kind, text, default, _MESH, metavar=metavar, group="sensor", flag=flag)
    for name, kind, text, default, metavar, flag in (
        ("standoff", "positive_float", "distance D from the sensor to the origin",
         "at infinity", "M", None),
        ("flood_radius", "positive_float", "a top-hat flood of this radius at the origin",
         "unbounded", "M", None),
        ("beam_waist", "positive_float", "a Gaussian beam of this 1/e² radius at the sensor",
         "a flood", "M", None),
        ("beam_divergence", "nonnegative_float", "its far-field 1/e² half-angle", "0",
         "RAD", None),
        ("beam_offset", "pair", "its pointing offset at the origin along the view's u, v (m)",
         "0,0", "U,V", None),
        ("pulse_energy", "positive_float", "transmitted energy per pulse",
         "none, relative units", "J", None),
        ("aperture_diameter", "positive_float", "receiver aperture diameter",
         "none, relative units", "M", "--aperture"),
        ("extinction", "nonnegative_float", "atmospheric extinction coefficient, two-way "
         "exp(-2 sigma R)", "0", "PER_M", None),
        ("wavelength", "positive_float", "laser wavelength", "1.064e-6", "M", None),
        ("optics_transmission", "unit_fraction", "receive optics' transmission", "1", None,
         None),
        ("quantum_efficiency", "unit_fraction", "detector quantum efficiency", "1", None,
         None)))

_BY_NAME = {o.name: o for o in OPTIONS}


def option(name: str) -> Option:
    """The :class:`Option` called ``name``.

    Parameters
    ----------
    name : str
        An option of :data:`OPTIONS` (the sensor flags of :data:`SENSOR_OPTIONS` are not
        looked up here).

    Returns
    -------
    Option
        Its record.

    Raises
    ------
    KeyError
        If no option of :data:`OPTIONS` has that name; the message lists them.
    """
    if name not in _BY_NAME:
        raise KeyError(f"no option {name!r}; options: {tuple(_BY_NAME)}")
    return _BY_NAME[name]


def options_of(model: str) -> tuple[str, ...]:
    """The names of the options ``model`` takes, in table order.

    Parameters
    ----------
    model : str
        One of :data:`MODELS` (``"analytic"``, ``"mesh"``, ``"pixel"``).

    Returns
    -------
    tuple of str
        The names of the :data:`OPTIONS` whose ``models`` include ``model``, in the
        table's order (the stream's options included; the sensor flags are not).

    Raises
    ------
    KeyError
        If ``model`` is not one of :data:`MODELS`.
    """
    if model not in MODELS:
        raise KeyError(f"model must be one of {MODELS}; got {model!r}")
    return tuple(o.name for o in OPTIONS if model in o.models)
