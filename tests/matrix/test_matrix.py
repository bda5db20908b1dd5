"""Bad input and faults to zero (issue 12): a matrix of bad calls and bad command lines.

Each case is a call of the public API (kind "api") or a command line run in this process
through ``meshladar.cli.main`` (kind "cli"), and what must happen to it:

- ``error``: refused with one clear error;
- ``warn``: accepted, with a MeshladarWarning;
- ``ok``: a valid edge input that must just work (its value checked where that is cheap).

:func:`run_case` classifies what did happen:

- ``clear``: api: a MeshladarError (ParameterError, GeometryError, PhantomSpecError,
  MaterialFileError, RunFolderError, ResultFileError: each also a builtin such as
  ValueError) whose message is one line naming the argument or file (one of the case's
  ``names``); cli: exit status 2 and one line on stderr (after argparse's usage lines, if
  any) starting ``meshladar...: error:``, naming the option or file, and no traceback;
- ``vague``: such an error, but its message is more than one line or names none of them;
- ``traceback``: api: any other exception (numpy's IndexError, TypeError, AttributeError,
  RecursionError, MemoryError, zlib.error...); cli: an exception out of ``main``, exit
  status 1 (meshladar's "internal error"), any other status, or a traceback on stderr;
- ``warned``: returned, and a MeshladarWarning was emitted;
- ``accepted``: returned without one;
- ``wrong``: returned, but the case's value check failed (or the case wrote a file beside
  its folder, as an output named after the folder);
- ``late``: the work started before the bad input was refused (the case names the
  functions it must not reach: the paper's and the studies' simulations, the benchmarks);
- ``hang``: only in the report below, which runs each case in a child process with a
  timeout (the tests themselves have no deadline).

An error case must come out ``clear``, a warn case ``warned``, an ok case ``accepted``.
An error or warn case that comes out ``accepted`` is silent nonsense.

Every case runs with the address space capped a few GiB above what the process already
uses, so an allocation the code should have refused is a MemoryError (a "traceback"), never
a machine out of memory; a case that could fork without bound runs only after a cheap check
that the code still refuses it.

Report::

    python tests/test_matrix.py --report [--before PATH] [--json FILE] [--only SUBSTRING]

runs every case in its own process (120 s timeout, 6 GiB address space) and prints the
counts per outcome and every mismatch. ``--before PATH`` (or the environment variable
MESHLADAR_MATRIX_BEFORE) puts PATH first on sys.path, to run the same matrix against an
older checkout; there, a case that fails because a name did not exist yet (``module
'meshladar' has no attribute ...``) is counted as ``n/a``.
"""

from __future__ import annotations

import contextlib
import glob
import inspect
import io
import json
import math
import os
import re
import sys
import warnings
from dataclasses import dataclass
from functools import cache, partial
from pathlib import Path

_BEFORE = os.environ.get("MESHLADAR_MATRIX_BEFORE")
if __name__ == "__main__" and "--before" in sys.argv:
    _BEFORE = sys.argv[sys.argv.index("--before") + 1]
if _BEFORE:
    sys.path.insert(0, os.path.abspath(_BEFORE))

import numpy as np  # noqa: E402

import meshladar as ml  # noqa: E402

nan, inf = math.nan, math.inf

#: What each expectation requires of the outcome.
EXPECTED = {"error": "clear", "warn": "warned", "ok": "accepted"}
#: Address space a case may add to what the process already uses.
GUARD_BYTES = 4 * 2**30


@dataclass
class Case:
    """One bad (or valid edge) input and what must happen to it."""

    id: str
    kind: str                 # "api" or "cli"
    call: object              # api: a callable (taking ``tmp``, the case's folder, if it
    #                           names that parameter); cli: argv, "{tmp}" standing for it
    expect: str               # "error", "warn" or "ok"
    names: tuple = ()         # an error's message must contain one of these
    setup: object = None      # setup(tmp): makes the files the case reads
    check: object = None      # check(value) (api) or check(tmp) (cli) -> bool, for ok/warn
    precheck: object = None   # () -> bool: safe to run (a fork bomb is refused up front)
    forbid: tuple = ()        # "module:function"s the case must not reach: bad input is
    #                           refused before the work starts
    skip_root: bool = False   # meaningless as root (permissions are not enforced)


CASES: list[Case] = []


def _names(names):
    return (names,) if isinstance(names, str) else tuple(names)


def api(id, call, expect, names=(), **kw):
    CASES.append(Case(f"api.{id}", "api", call, expect, _names(names), **kw))


def cli(id, argv, expect, names=(), **kw):
    CASES.append(Case(f"cli.{id}", "cli", list(argv), expect, _names(names), **kw))


# ------------------------------------------------------------------ shared inputs (lazy:
# built on first use, so that an older meshladar without a name fails that case only)

@cache
def _dg():
    return ml.materials.DARK_GRAY


@cache
def _al():
    return ml.materials.ALUMINUM


@cache
def _sphere():
    """A 320-face sphere of radius 0.5 at the origin."""
    return ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)], [_dg()])


@cache
def _disk():
    return ml.Scene([ml.Disk((0.0, 0.0), 0.5, _dg())])


@cache
def _lad():
    """Two views, eight bins over the sphere and the disk."""
    return ml.Ladar(np.array([0.0, 90.0]), np.linspace(-0.6, 0.6, 9))


@cache
def _sino():
    """32 views x 8 bins of a uniform return (enough views for its bins)."""
    return ml.Sinogram(np.ones((32, 8)), angles_deg=np.arange(32) * 360.0 / 32,
                       bin_edges=np.linspace(-1, 1, 9))


@cache
def _hits():
    return ml.trace(_sphere(), _lad())


def _sr(**kw):
    return ml.SandfordRobertson(**dict(dict(rho_d=0.032, epsilon=0.877, b=0.1, e=0.17), **kw))


def _trimesh():
    import trimesh

    return trimesh


# ------------------------------------------------------------------ files

DIR = object()                                 # a folder where a file is expected
JUNK = bytes(range(256)) * 16                  # binary junk
DEEP_TOML = b"a = " + b"[" * 5000 + b"]" * 5000 + b"\n"
NOT_UTF8_TOML = b"[paint]\nrho_d = 0.1\n\xff\xfe\n"
NOT_UTF8_OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\xff\xfe\x80 f 1 2 3\n"
LONG_INT_TOML = b"n_bins = " + b"9" * 5000 + b"\n"
TABLE = b"[mine]\nrho_d = 0.1\nepsilon = 0.5\nb = 0.1\ne = 0.2\n"
DISK_SPEC = (b'[ladar]\nn_bins = 16\nbin_width = 0.1\n'
             b'angles_deg = { start = 0.0, stop = 360.0, step = 90.0 }\n'
             b'[[shape]]\nname = "d"\nkind = "disk"\ncenter = [0, 0]\nradius = 0.5\n'
             b'material = "dark_gray"\n')


def _spec(**fields):
    """DISK_SPEC with its [[shape]] or [ladar] fields replaced (TOML values as text)."""
    text = DISK_SPEC.decode()
    for key, value in fields.items():
        text = re.sub(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
    return text.encode()


@cache
def _stl_bytes():
    return _trimesh().creation.icosphere(subdivisions=1, radius=0.5).export(file_type="stl")


def _stl(path):
    path.write_bytes(_stl_bytes())


def _truncated_stl(path):
    path.write_bytes(_stl_bytes()[: len(_stl_bytes()) // 2])


def _result(path):
    ml.io.save_sinogram(path, _sino())


def _truncated_result(path):
    buf = path.with_suffix(".full")
    ml.io.save_sinogram(buf, _sino())
    data = buf.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    buf.unlink()


def _image_result(path):
    ml.io.save_result(path, {"image": np.ones((4, 4))}, {"kind": "image"})


def _deep_meta_result(path):
    np.savez(path, values=np.zeros((2, 2)), __meta__=np.array("[" * 5000 + "]" * 5000))


def _no_meta_result(path):
    np.savez(path, values=np.zeros((2, 2)))


def _pickled_result(path):
    np.savez(path, values=np.array([{}], dtype=object), __meta__=np.array("{}"))


def _read_only(path):
    path.mkdir()
    path.chmod(0o555)


def files(spec):
    """A setup writing {relative path: bytes, DIR or a callable(path)} into the folder."""
    def setup(tmp):
        for name, data in spec.items():
            path = tmp / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if data is DIR:
                path.mkdir()
            elif callable(data):
                data(path)
            else:
                path.write_bytes(data)
    return setup


#: Bad contents of a file argument (None: the file is missing).
BAD_FILES = {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "not-utf8": NOT_UTF8_TOML}
BAD_TOML = dict(BAD_FILES, deep=DEEP_TOML, truncated=b"[paint]\nrho_d = 0.")


def _file_cases(prefix, kind, make, suffix, contents, names, expect="error", **kw):
    """One case per bad content of the file ``make`` reads (missing: not written)."""
    for key, data in contents.items():
        name = f"bad{suffix}"
        setup = None if data is None else files({name: data})
        if kind == "api":
            api(f"{prefix}={key}", partial(_in_tmp, make, name), expect, names, setup=setup,
                **kw)
        else:
            cli(f"{prefix}={key}", make(f"{{tmp}}/{name}"), expect, names, setup=setup, **kw)


def _in_tmp(make, name, tmp):
    return make(tmp / name)


#: Bad values of a scalar real parameter.
SCALARS = {"nan": nan, "inf": inf, "-inf": -inf, "neg": -1.0, "zero": 0.0, "huge": 1e300,
           "str": "0.5", "none": None, "bool": True, "list": [0.1, 0.2]}
#: Bad values of a count (an integer >= 1).
COUNTS = {"zero": 0, "neg": -1, "float": 1.5, "nan": nan, "str": "8", "none": None,
          "bool": True, "huge": 10**10}


def scalar_cases(prefix, make, param, values=SCALARS, *, ok=(), warn=(), names=None,
                 checks=None):
    """One case per bad value of one parameter: ``make(value)``; every value an error
    unless listed in ``ok`` or ``warn``."""
    for key, value in values.items():
        expect = "ok" if key in ok else "warn" if key in warn else "error"
        api(f"{prefix}.{param}={key}", partial(make, value), expect,
            names or (param,), check=(checks or {}).get(key))


def _finite(x):
    values = getattr(x, "values", x)
    return bool(np.all(np.isfinite(values)))


# ================================================================== the API

# ------------------------------------------------------------------ BRDF
for _p in ("rho_d", "epsilon", "b", "e"):
    scalar_cases("SR", lambda v, p=_p: _sr(**{p: v}), _p, ok=() if _p == "e" else ("zero",),
                 names=(f"{_p} must",),
                 checks={"zero": lambda m, p=_p: getattr(m, p) == 0.0})
api("SR.e=1e-12", lambda: _sr(e=1e-12), "ok")
api("SR.e=1e-13", lambda: _sr(e=1e-13), "error", "e must")
api("SR.e=np.float64", lambda: _sr(e=np.float64(0.2)), "ok", check=lambda m: m.e == 0.2)
api("SR.rho_d=np.int64", lambda: _sr(rho_d=np.int64(0)), "ok")
api("SR.lobes=x", lambda: _sr(lobes="x"), "error", "lobes")
api("SR.lobes=None", lambda: _sr(lobes=None), "error", "lobes")
api("SR.lobes=3", lambda: _sr(lobes=3), "error", "lobes")
api("SR.lobes=BOTH", lambda: _sr(lobes="BOTH"), "error", "lobes")
api("SR.name=3", lambda: _sr(name=3), "error", "name")
api("SR.not-energy-conserving", lambda: _sr(rho_d=0.5, epsilon=0.9), "error",
    ("rho_d", "energy"))
api("SR.diffuse-b0.99-warns", lambda: ml.SandfordRobertson(1.0, 0.0, 0.99, 1.0,
                                                           lobes="diffuse"), "warn")
api("SR.specular-only", lambda: ml.SandfordRobertson(0.0, 0.0, 0.0, 0.007, lobes="specular"),
    "ok")

_THETA = {"nan": nan, "inf": inf, "-inf": -inf, "neg": -0.3, "zero": 0.0, "huge": 1e300,
          "str": "x", "none": None, "ragged": [[0.1], [0.2, 0.3]], "list": [0.1, 0.2],
          "nan-in-list": [0.1, nan], "empty": []}
scalar_cases("SR.monostatic", lambda v: _dg().monostatic(v), "theta", _THETA,
             ok=("neg", "zero", "huge", "list", "empty"),
             checks={"neg": lambda f: f == _dg().monostatic(0.3), "huge": _finite,
                     "list": lambda f: np.shape(f) == (2,), "empty": lambda f: np.size(f) == 0})
api("SR.monostatic.projected=no", lambda: _dg().monostatic(0.1, projected="no"), "error",
    "projected")
api("SR.monostatic.projected=None", lambda: _dg().monostatic(0.1, projected=None), "error",
    "projected")
api("SR.monostatic.90deg-projected", lambda: _al().monostatic(np.pi / 2, projected=True),
    "ok", check=lambda f: math.isfinite(f) and f > 0)
for _fn in ("specular_reflectance", "diffuse_reflectance", "emissivity"):
    api(f"SR.{_fn}(nan)", lambda f=_fn: getattr(_dg(), f)(nan), "error", "theta")
    api(f"SR.{_fn}(str)", lambda f=_fn: getattr(_dg(), f)("x"), "error", "theta")

_VEC = {"nan": (nan, 0, 1), "zero": (0, 0, 0), "short": (0, 1), "str": "x", "none": None,
        "inf": (0, inf, 1), "ragged": [[0, 0, 1], [0, 1]]}
for _arg, _pos in (("incident", 0), ("reflected", 1), ("normal", 2)):
    for _key, _v in _VEC.items():
        def _call(v=_v, pos=_pos):
            args = [(0, 0, 1), (0, 0.2, 1), (0, 0, 1)]
            args[pos] = v
            return _dg().evaluate(*args)
        api(f"SR.evaluate.{_arg}={_key}", _call, "error", _arg)
api("SR.evaluate.shapes", lambda: _dg().evaluate(np.ones((2, 3)), np.ones((3, 3)),
                                                 np.ones((3, 3))), "error", "broadcast")
api("SR.evaluate.projected=x", lambda: _dg().evaluate((0, 0, 1), (0, 0, 1), projected="x"),
    "error", "projected")
api("SR.evaluate.opposite", lambda: _dg().evaluate((1, 0, 0), (-1, 0, 0)), "ok",
    check=_finite)
api("SR.evaluate_angles.theta_i=nan", lambda: _dg().evaluate_angles(nan, 0.1), "error",
    "theta_i")
api("SR.evaluate_angles.theta_r=inf", lambda: _dg().evaluate_angles(0.1, inf), "error",
    "theta_r")
api("SR.evaluate_angles.delta_phi=str", lambda: _dg().evaluate_angles(0.1, 0.1, "x"),
    "error", "delta_phi")
api("SR.evaluate_angles.delta_phi=None", lambda: _dg().evaluate_angles(0.1, 0.1, None),
    "error", "delta_phi")
api("SR.evaluate_angles.mirror", lambda: _al().evaluate_angles(0.3, 0.3, np.pi), "ok",
    check=lambda f: f > 1.0)

# ------------------------------------------------------------------ coating helpers
for _key, _v in {"nan": nan, "neg": -0.1, "above-1": 2.0, "str": "x", "none": None}.items():
    api(f"materials.lambertian.rho_d={_key}", lambda v=_v: ml.materials.lambertian(v),
        "error", "rho_d")
    api(f"materials.glint.rho_s={_key}", lambda v=_v: ml.materials.glint(0.1, rho_s=v),
        "error", "rho_s")
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -0.1, "above-1": 2.0, "str": "x"}.items():
    api(f"materials.glint.e={_key}", lambda v=_v: ml.materials.glint(v), "error", "e must")
api("materials.lambertian.rho_d=0", lambda: ml.materials.lambertian(0.0), "ok",
    check=lambda m: m.monostatic(0.0) == 0.0)

# ------------------------------------------------------------------ the BRDF protocol: the
# other built-in models, and a user's own


def _brdf(model, *args, **kw):
    return getattr(ml.brdf, model)(*args, **kw)


scalar_cases("Lambertian", lambda v: _brdf("Lambertian", v), "albedo", ok=("zero",),
             checks={"zero": lambda m: m.monostatic(0.0) == 0.0})
for _p, _i in (("kd", 0), ("ks", 1)):
    for _key in ("nan", "neg", "huge", "str", "none"):
        def _phong(v=SCALARS[_key], i=_i):
            args = [0.3, 0.3, 10.0]
            args[i] = v
            return _brdf("Phong", *args)
        api(f"Phong.{_p}={_key}", _phong, "error", _p)
for _key, _v in {"nan": nan, "neg": -1.0, "huge": 1e300, "str": "x", "inf": inf}.items():
    api(f"Phong.exponent={_key}", lambda v=_v: _brdf("Phong", 0.3, 0.3, v), "error", "exponent")
api("Phong.exponent=0", lambda: _brdf("Phong", 0.3, 0.3, 0.0), "ok",
    check=lambda m: m.monostatic(0.0) > 0)
api("Phong.not-energy-conserving", lambda: _brdf("Phong", 0.7, 0.7, 10.0), "error",
    ("kd + ks",))
for _key, _v in {"zero": 0.0, "tiny": 1e-5, "nan": nan, "above-1": 2.0, "str": "x",
                 "none": None}.items():
    api(f"GGX.alpha={_key}", lambda v=_v: _brdf("GGX", v), "error", "alpha")
for _key, _v in {"neg": -0.1, "above-1": 2.0, "nan": nan, "none": None}.items():
    api(f"GGX.reflectance={_key}", lambda v=_v: _brdf("GGX", 0.3, v), "error", "reflectance")
api("GGX.grazing", lambda: _brdf("GGX", 1e-4).monostatic(np.pi / 2, projected=True), "ok",
    check=lambda f: math.isfinite(f))
for _key, _t, _v in (("theta-from-10", [10, 90], [1, 1]), ("theta-to-80", [0, 80], [1, 1]),
                     ("theta-decreasing", [0, 60, 30, 90], [1, 1, 1, 1]),
                     ("theta-one", [0], [1]), ("theta-nan", [0, nan, 90], [1, 1, 1]),
                     ("theta-str", "x", [1, 1]), ("theta-2d", [[0, 90]], [[1, 1]])):
    api(f"Tabulated.{_key}", lambda t=_t, v=_v: _brdf("Tabulated", t, v), "error", "theta_deg")
for _key, _v in (("negative", [1, -1]), ("nan", [1, nan]), ("short", [1]), ("str", "x"),
                 ("inf", [inf, 1])):
    api(f"Tabulated.values-{_key}", lambda v=_v: _brdf("Tabulated", [0, 90], v), "error",
        "values")
api("Tabulated.projected_values=yes", lambda: _brdf("Tabulated", [0, 90], [1, 1],
                                                    projected_values="yes"),
    "error", "projected_values")
api("Tabulated.bistatic", lambda: ml.simulate(ml.Scene.from_parts(
    [ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)], [_brdf("Tabulated", [0, 90], [1, 1])]),
    _lad(), model="mesh", receiver=(0, 1, 1)), "error", ("bistatic", "receiver"))
for _model, _args in (("Lambertian", (0.5,)), ("Phong", (0.3, 0.3, 10.0)), ("GGX", (0.3,)),
                      ("Tabulated", ([0, 90], [1, 1]))):
    api(f"{_model}.name=3", lambda m=_model, a=_args: _brdf(m, *a, name=3), "error", "name")
    api(f"{_model}.analytic", lambda m=_model, a=_args: ml.simulate(
        ml.Scene([ml.Disk((0, 0), 0.5, _brdf(m, *a))]), _lad()), "ok",
        check=lambda s: _finite(s) and s.values.sum() > 0)
api("Disk.material=class", lambda: ml.Disk((0, 0), 0.5, ml.brdf.Lambertian), "error",
    "material")


@cache
def _user_brdfs():
    """A user's models that break the protocol: NaN, negative, wrong shape, no projected."""
    class NaNModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return np.full(np.shape(cos_theta), nan)

    class NegativeModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return -np.ones(np.shape(cos_theta))

    class ShapeModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return np.ones(3)

    class NoProjectedModel(ml.brdf.BRDF):
        pass

    return {"nan": NaNModel(), "negative": NegativeModel(), "shape": ShapeModel(),
            "no-projected": NoProjectedModel()}


for _key, _name in (("nan", "NaNModel"), ("negative", "NegativeModel"),
                    ("shape", "ShapeModel"), ("no-projected", "NoProjectedModel")):
    api(f"user-BRDF.{_key}.monostatic", lambda k=_key: _user_brdfs()[k].monostatic(0.1),
        "error", _name)
    api(f"user-BRDF.{_key}.analytic", lambda k=_key: ml.simulate(
        ml.Scene([ml.Disk((0, 0), 0.5, _user_brdfs()[k])]), _lad()), "error", _name)
    api(f"user-BRDF.{_key}.mesh", lambda k=_key: ml.simulate(ml.Scene.from_parts(
        [ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)], [_user_brdfs()[k]]), _lad(),
        model="mesh"), "error", _name)

# ------------------------------------------------------------------ shapes and scenes
_CENTERS = {"nan": (nan, 0.0), "inf": (inf, 0.0), "short": (0.0,), "long": (0, 0, 0),
            "str": "ab", "none": None, "nested": [[0, 0]]}
for _key, _v in _CENTERS.items():
    api(f"Disk.center={_key}", lambda v=_v: ml.Disk(v, 0.5, _dg()), "error", "center")
    api(f"Ellipse.center={_key}", lambda v=_v: ml.Ellipse(v, (0.5, 0.3), 0.0, _dg()), "error",
        "center")
scalar_cases("Disk", lambda v: ml.Disk((0.0, 0.0), v, _dg()), "radius", ok=("huge",))
api("Disk.material=str", lambda: ml.Disk((0, 0), 0.5, "dark_gray"), "error", "material")
api("Disk.material=None", lambda: ml.Disk((0, 0), 0.5, None), "error", "material")
api("Disk.name=3", lambda: ml.Disk((0, 0), 0.5, _dg(), name=3), "error", "name")
for _key, _v in {"nan": (nan, 0.3), "inf": (0.5, inf), "short": (0.5,), "neg": (0.5, -0.3),
                 "zero": (0.0, 0.3), "str": "ab", "none": None,
                 "three": (0.5, 0.3, 0.1)}.items():
    api(f"Ellipse.semi_axes={_key}", lambda v=_v: ml.Ellipse((0, 0), v, 0.0, _dg()), "error",
        "semi_axes")
scalar_cases("Ellipse", lambda v: ml.Ellipse((0, 0), (0.5, 0.3), v, _dg()), "angle_deg",
             ok=("neg", "zero", "huge"))
api("Ellipse.material=str", lambda: ml.Ellipse((0, 0), (0.5, 0.3), 0.0, "x"), "error",
    "material")

api("Scene.shapes=[]", lambda: ml.Scene([]), "error", "shapes")
api("Scene.shapes=None", lambda: ml.Scene(None), "error", "shapes")
api("Scene.shapes=5", lambda: ml.Scene(5), "error", "shapes")
api("Scene.shapes=[str]", lambda: ml.Scene(["disk"]), "error", "shapes[0]")
api("Scene.shapes=Disk", lambda: ml.Scene(ml.Disk((0, 0), 0.5, _dg())), "error", "shapes")
api("Scene.overlap", lambda: ml.Scene([ml.Disk((0, 0), 0.5, _dg()),
                                       ml.Disk((0.5, 0), 0.5, _dg())]), "error", "overlap")
api("Scene.overlap-ellipses", lambda: ml.Scene([
    ml.Ellipse((0, 0), (0.6, 0.2), 0.0, _dg()), ml.Ellipse((0, 0), (0.6, 0.2), 90.0, _dg())]),
    "error", "overlap")
api("Scene.same-disk-twice", lambda: ml.Scene([ml.Disk((0, 0), 0.5, _dg())] * 2), "error",
    "overlap")
api("Scene.touching", lambda: ml.Scene([ml.Disk((-0.3, 0), 0.4, _dg()),
                                        ml.Disk((0.4, 0), 0.3, _al())]), "ok",
    check=lambda s: len(s) == 2)
api("Scene.generator", lambda: ml.Scene(ml.Disk((x, 0), 0.1, _dg()) for x in (0, 1)), "ok",
    check=lambda s: len(s) == 2)


def _part(vertices=((0, 0, 0), (1, 0, 0), (0, 1, 0)), faces=((0, 1, 2),), material=0):
    return ml.meshes.MeshPart(np.array(vertices, dtype=float), np.array(faces), material)


api("Scene.from_parts.materials=[]", lambda: ml.Scene.from_parts([_part()], []), "error",
    "material")
api("Scene.from_parts.materials=[str]", lambda: ml.Scene.from_parts([_part()], ["x"]),
    "error", "materials[0]")
api("Scene.from_parts.materials=str", lambda: ml.Scene.from_parts([_part()], "dark_gray"),
    "error", "materials")
api("Scene.from_parts.parts=[]", lambda: ml.Scene.from_parts([], [_dg()]), "error",
    ("parts", "faces"))
api("Scene.from_parts.parts=[str]", lambda: ml.Scene.from_parts(["x"], [_dg()]), "error",
    "parts")
api("Scene.from_parts.index=1", lambda: ml.Scene.from_parts([_part(material=1)], [_dg()]),
    "error", "material")
api("MeshPart.vertices=nan", lambda: _part(vertices=((nan, 0, 0), (1, 0, 0), (0, 1, 0))),
    "error", "vertices")
api("MeshPart.vertices=2d", lambda: _part(vertices=((0, 0), (1, 0), (0, 1))), "error",
    "vertices")
api("MeshPart.faces=float", lambda: _part(faces=((0.0, 1.0, 2.5),)), "error", "faces")
api("MeshPart.faces=out-of-range", lambda: _part(faces=((0, 1, 3),)), "error", "faces")
api("MeshPart.faces=negative", lambda: _part(faces=((0, 1, -1),)), "error", "faces")
api("Scene.from_parts.degenerate-only", lambda: ml.Scene.from_parts(
    [_part(vertices=((0, 0, 0), (1, 0, 0), (2, 0, 0)))], [_dg()]), "error", "faces")
api("Scene.from_parts.inverted-warns", lambda: ml.Scene.from_parts(
    [ml.meshes.MeshPart(_sphere().parts[0].vertices, _sphere().parts[0].faces[:, ::-1], 0)],
    [_dg()]), "warn")

# mesh files and trimesh objects
_file_cases("Scene.from_mesh.stl", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".stl",
            {"missing": None, "dir": DIR, "empty": b"", "whitespace": b"  \n\t\n",
             "junk": JUNK, "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("Scene.from_mesh.obj", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".obj",
            {"junk": JUNK, "not-utf8": NOT_UTF8_OBJ, "text": b"hello world\n"}, ("bad.obj",))
_file_cases("Scene.from_mesh.ply", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".ply",
            {"point-cloud": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                            b"property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n"
                            b"0 1 0\n"}, ("bad.ply",))
_file_cases("Scene.from_mesh.toml", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".toml",
            {"spec": DISK_SPEC}, ("bad.toml",))
_file_cases("Scene.from_mesh.dat", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".dat",
            {"binary-stl": _stl}, (), expect="ok")
api("Scene.from_mesh.None", lambda: ml.Scene.from_mesh(None, _dg()), "error", "mesh")
api("Scene.from_mesh.int", lambda: ml.Scene.from_mesh(3, _dg()), "error", "mesh")
api("Scene.from_mesh.empty-trimesh", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(), _dg()),
    "error", "mesh")
api("Scene.from_mesh.nan-vertices", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(
    vertices=[[nan, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]], process=False), _dg()),
    "error", "finite")
api("Scene.from_mesh.no-faces", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(
    vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=np.zeros((0, 3), int)), _dg()),
    "error", ("faces", "point"))
api("Scene.from_mesh.point-cloud", lambda: ml.Scene.from_mesh(
    _trimesh().PointCloud([[0, 0, 0], [1, 0, 0]]), _dg()), "error", "point")
api("Scene.from_mesh.empty-scene", lambda: ml.Scene.from_mesh(_trimesh().Scene(), _dg()),
    "error", "mesh")


def _box(**kw):
    return ml.Scene.from_mesh(_trimesh().creation.box(), **kw)


api("Scene.from_mesh.material=None", lambda: _box(), "error", "material")
api("Scene.from_mesh.material=str", lambda: _box(material="dark_gray"), "error", "material")
api("Scene.from_mesh.materials=unknown-part", lambda: _box(material=_dg(),
                                                           materials={"nope": _al()}),
    "error", "nope")
api("Scene.from_mesh.materials=list", lambda: _box(material=_dg(), materials=[_al()]),
    "error", "materials")
api("Scene.from_mesh.transform=nan", lambda: _box(material=_dg(),
                                                  transform=np.full((4, 4), nan)),
    "error", "transform")
api("Scene.from_mesh.transform=3x3", lambda: _box(material=_dg(), transform=np.eye(3)),
    "error", "transform")
api("Scene.from_mesh.transform=singular", lambda: _box(material=_dg(),
                                                       transform=np.zeros((4, 4))),
    "error", ("transform", "faces"))
api("Scene.from_mesh.face_materials=short", lambda: _box(materials=[_dg()],
                                                         face_materials=[0, 0]),
    "error", "face_materials")
api("Scene.from_mesh.face_materials=index", lambda: _box(materials=[_dg()],
                                                         face_materials=[1] * 12),
    "error", ("material", "face_materials"))
api("Scene.from_mesh.face_materials-without-list", lambda: _box(
    material=_dg(), face_materials=[0] * 12), "error", "materials")
api("Scene.from_mesh.box", lambda: _box(material=_dg()), "ok",
    check=lambda s: s.report["faces"] == 12)

for _key, _v in {"2": 2, "zero": 0, "neg": -1, "float": 1.5, "str": "x", "none": None,
                 "bool": True, "huge": 10**8}.items():
    api(f"Scene.tessellate.segments={_key}", lambda v=_v: _disk().tessellate(v), "error",
        "segments")
api("Scene.tessellate.segments=3", lambda: _disk().tessellate(3), "ok",
    check=lambda s: s.is_mesh)
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "str": "x", "inf": inf}.items():
    api(f"Scene.tessellate.height={_key}", lambda v=_v: _disk().tessellate(8, height=v),
        "error", "height")
for _key, _v in {"nan": nan, "str": "x", "none": None}.items():
    api(f"Scene.tessellate.z0={_key}", lambda v=_v: _disk().tessellate(8, z0=v), "error", "z0")
api("Scene.tessellate.of-mesh", lambda: _sphere().tessellate(8), "error", "tessellate")

# ------------------------------------------------------------------ the ladar
_EDGES = np.linspace(-1, 1, 9)
for _key, _v in {"nan": [0.0, nan], "inf": [inf], "empty": [], "none": None, "str": "x",
                 "2d": [[0.0, 90.0]], "scalar": 5.0, "ragged": [[0.0], [1.0, 2.0]]}.items():
    api(f"Ladar.angles_deg={_key}", lambda v=_v: ml.Ladar(v, _EDGES), "error", "angles_deg")
api("Ladar.angles_deg=huge", lambda: ml.Ladar([1e300], _EDGES), "ok")
api("Ladar.angles_deg=negative", lambda: ml.Ladar([-90.0, 720.0], _EDGES), "ok",
    check=lambda lad: lad.n_views == 2)
for _key, _v in {"nan": [0.0, nan], "decreasing": [1.0, 0.0], "one": [0.0],
                 "repeated": [0.0, 0.0, 1.0], "none": None, "str": "x", "2d": [[0.0, 1.0]],
                 "infinite": [-inf, inf], "empty": []}.items():
    api(f"Ladar.bin_edges={_key}", lambda v=_v: ml.Ladar([0.0], v), "error", "bin_edges")
api("Ladar.bin_edges=huge", lambda: ml.Ladar([0.0], [-1e300, 1e300]), "ok")
for _key, _v in {"zero": [[0, 0, 0]], "nan": [[nan, 0, 1]], "1d": [0, 0, 1],
                 "2-wide": [[1, 0]], "empty": np.zeros((0, 3)), "str": "x"}.items():
    api(f"Ladar.view_vectors={_key}", lambda v=_v: ml.Ladar(None, _EDGES, view_vectors=v),
        "error", "view_vectors")
api("Ladar.view_vectors+angles-lengths", lambda: ml.Ladar([0.0, 1.0], _EDGES,
                                                          view_vectors=[[1, 0, 0]]),
    "error", ("angles_deg", "view_vectors"))
api("Ladar.view_vectors+angles-disagree", lambda: ml.Ladar([90.0], _EDGES,
                                                           view_vectors=[[1, 0, 0]]),
    "error", ("angles_deg", "view_vectors"))
api("Ladar.view_vectors=pole", lambda: ml.Ladar(None, _EDGES, view_vectors=[[0, 0, 1]]), "ok",
    check=lambda lad: not lad.planar)
api("Ladar.huge-sinogram", lambda: ml.Ladar(np.arange(10**6), np.linspace(-1, 1, 10**4)),
    "error", "ladar")

for _key, _v in COUNTS.items():
    api(f"Ladar.centered.n_bins={_key}", lambda v=_v: ml.Ladar.centered(v, 0.1), "error",
        "n_bins")
api("Ladar.centered.n_bins=1", lambda: ml.Ladar.centered(1, 0.1), "ok",
    check=lambda lad: lad.n_bins == 1)
scalar_cases("Ladar.centered", lambda v: ml.Ladar.centered(8, v), "bin_width", ok=("huge",))
scalar_cases("Ladar.centered", lambda v: ml.Ladar.centered(8, 0.1, center=v), "center",
             ok=("neg", "zero"), names=("center", "bin_edges"))
api("Ladar.centered.angles_deg=[]", lambda: ml.Ladar.centered(8, 0.1, angles_deg=[]), "error",
    "angles_deg")
api("Ladar.centered.angles_deg=nan", lambda: ml.Ladar.centered(8, 0.1, angles_deg=[nan]),
    "error", "angles_deg")
scalar_cases("Ladar.paper", lambda v: ml.Ladar.paper(v), "radius", ok=("huge",))
api("Ladar.paper.n_bins=0", lambda: ml.Ladar.paper(n_bins=0), "error", "n_bins")

api("Ladar.covering.neither", lambda: ml.Ladar.covering(_disk()), "error",
    ("bin_width", "n_bins"))
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "str": "x", "tiny": 1e-12,
                 "inf": inf}.items():
    api(f"Ladar.covering.bin_width={_key}", lambda v=_v: ml.Ladar.covering(_disk(),
                                                                           bin_width=v),
        "error", "bin_width")
api("Ladar.covering.bin_width=huge", lambda: ml.Ladar.covering(_disk(), bin_width=1e300),
    "ok", check=lambda lad: lad.n_bins == 1)
for _key, _v in {"zero": 0, "float": 1.5, "str": "x", "huge": 10**10}.items():
    api(f"Ladar.covering.n_bins={_key}", lambda v=_v: ml.Ladar.covering(_disk(), n_bins=v),
        "error", "n_bins")
for _key, _v in {"neg": -1.0, "nan": nan, "str": "x", "inf": inf}.items():
    api(f"Ladar.covering.margin={_key}", lambda v=_v: ml.Ladar.covering(_disk(), n_bins=8,
                                                                        margin=v),
        "error", "margin")
api("Ladar.covering.scene=str", lambda: ml.Ladar.covering("disk", n_bins=8), "error", "scene")
api("Ladar.covering.scene=None", lambda: ml.Ladar.covering(None, n_bins=8), "error", "scene")
api("Ladar.covering.angles_deg=[]", lambda: ml.Ladar.covering(_disk(), n_bins=8,
                                                              angles_deg=[]),
    "error", "angles_deg")
api("Ladar.covering.view_vectors=zero", lambda: ml.Ladar.covering(
    _sphere(), n_bins=8, view_vectors=[[0, 0, 0]]), "error", "view_vectors")
api("Ladar.covering.one-bin-mesh", lambda: ml.Ladar.covering(_sphere(), n_bins=1), "ok",
    check=lambda lad: lad.n_bins == 1)
api("Ladar.covering.off-axis-warns", lambda: ml.Ladar.covering(ml.Scene.from_parts(
    [ml.meshes.sphere((100, 0, 0), 0.5, 0, subdivisions=1)], [_dg()]), n_bins=8), "warn")

# ------------------------------------------------------------------ simulate


def _mesh_sim(**kw):
    return ml.simulate(_sphere(), _lad(), model="mesh", **kw)


def _pixel_sim(**kw):
    return ml.simulate(_disk(), _lad(), model="pixel", **kw)


api("simulate.scene=str", lambda: ml.simulate("disk", _lad()), "error", "scene")
api("simulate.scene=None", lambda: ml.simulate(None, _lad()), "error", "scene")
api("simulate.ladar=str", lambda: ml.simulate(_disk(), "ladar"), "error", "ladar")
api("simulate.ladar=None", lambda: ml.simulate(_disk(), None), "error", "ladar")
for _key, _v in {"x": "x", "none": None, "int": 3, "upper": "MESH"}.items():
    api(f"simulate.model={_key}", lambda v=_v: ml.simulate(_disk(), _lad(), model=v), "error",
        "model")
api("simulate.unknown-option", lambda: _mesh_sim(bogus=1), "error", "bogus")
api("simulate.radiometry=power", lambda: _mesh_sim(radiometry="power"), "ok",
    check=lambda s: s.info["radiometry"] == "power")
api("simulate.radiometry=watts", lambda: _mesh_sim(radiometry="watts"), "error", "radiometry")
api("simulate.analytic.radiometry=None", lambda: ml.simulate(_disk(), _lad(), radiometry=None),
    "error", "radiometry")
api("simulate.segments", lambda: _mesh_sim(segments=64), "error", "segments")
api("simulate.analytic-of-mesh", lambda: ml.simulate(_sphere(), _lad()), "error", "mesh")
api("simulate.analytic.jobs=0", lambda: ml.simulate(_disk(), _lad(), jobs=0), "error", "jobs")
api("simulate.analytic.progress=str", lambda: ml.simulate(_disk(), _lad(), progress="yes"),
    "error", "progress")
api("simulate.pixel.progress=None", lambda: ml.simulate(_disk(), _lad(), model="pixel",
                                                        progress=None), "error", "progress")
api("simulate.pixel-of-mesh", lambda: ml.simulate(_sphere(), _lad(), model="pixel"), "error",
    "mesh")
api("simulate.analytic.off-plane", lambda: ml.simulate(
    _disk(), ml.Ladar(None, _EDGES, view_vectors=[[0, 0, 1]])), "error", "view")
api("simulate.analytic", lambda: ml.simulate(_disk(), _lad()), "ok",
    check=lambda s: s.shape == (2, 8) and _finite(s) and s.values.sum() > 0)
api("simulate.analytic.bins-miss-warns", lambda: ml.simulate(_disk(), ml.Ladar([0.0],
                                                                               [5.0, 6.0])),
    "warn")
api("simulate.mesh.bins-miss-warns", lambda: ml.simulate(_sphere(), ml.Ladar([0.0],
                                                                             [5.0, 6.0]),
                                                         model="mesh"), "warn")
api("simulate.analytic.huge-disk-warns", lambda: ml.simulate(
    ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), _lad()), "warn")
api("simulate.analytic.huge-disk-covered", lambda: ml.simulate(
    ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), ml.Ladar.covering(
        ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), n_bins=8, angles_deg=[0.0, 90.0])), "ok",
    check=lambda s: _finite(s) and s.values.max() > 0)


def _sized_sphere(radius):
    scene = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), radius, 0, subdivisions=1)],
                                [_dg()])
    return ml.simulate(scene, ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0, 90.0]),
                       model="mesh")


api("simulate.mesh.size=1e40", lambda: _sized_sphere(1e40), "error", "scene")
api("simulate.mesh.size=1e-40", lambda: _sized_sphere(1e-40), "error", "scene")
api("simulate.mesh.size=1e25", lambda: _sized_sphere(1e25), "ok", check=_finite)
api("simulate.pixel", lambda: _pixel_sim(), "ok", check=_finite)
scalar_cases("simulate.pixel", lambda v: _pixel_sim(pixel_size=v), "pixel_size",
             ok=("none",))
api("simulate.pixel.pixel_size=tiny", lambda: _pixel_sim(pixel_size=1e-6), "error",
    "pixel_size")
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "tiny": 1e-12, "str": "x"}.items():
    api(f"simulate.pixel.ray_spacing={_key}", lambda v=_v: _pixel_sim(ray_spacing=v), "error",
        "ray_spacing")

api("simulate.mesh", lambda: _mesh_sim(), "ok",
    check=lambda s: s.shape == (2, 8) and _finite(s) and s.values.sum() > 0)
for _key, _v in {"x": "x", "int": 3, "empty": "", "upper": "3D"}.items():
    api(f"simulate.mesh.mode={_key}", lambda v=_v: _mesh_sim(mode=v), "error", "mode")
api("simulate.mesh.mode=slice", lambda: _mesh_sim(mode="slice"), "ok", check=_finite)
for _v in ("optix", "", None, 3):
    api(f"simulate.mesh.backend={_v!r}", lambda v=_v: _mesh_sim(backend=v), "error", "backend")
for _v in ("auto", "packets", "embreex"):
    api(f"simulate.mesh.backend={_v}", lambda v=_v: _mesh_sim(backend=v), "ok", check=_finite)
api("simulate.analytic.backend", lambda: ml.simulate(_disk(), _lad(), backend="packets"),
    "error", "backend")
for _key, _v in {"nan": nan, "inf": inf, "str": "x", "bool": True, "list": [0.0]}.items():
    api(f"simulate.mesh.z0={_key}", lambda v=_v: _mesh_sim(mode="slice", z0=v), "error", "z0")
api("simulate.mesh.z0-with-3d", lambda: _mesh_sim(mode="3d", z0=0.1), "error", "z0")
api("simulate.mesh.z0-outside-warns", lambda: _mesh_sim(mode="slice", z0=5.0), "warn")
scalar_cases("simulate.mesh", lambda v: _mesh_sim(ray_spacing=v), "ray_spacing", ok=("none",),
             warn=("huge",))      # rays wider than the target: all zeros, saying why
api("simulate.mesh.ray_spacing=tiny", lambda: _mesh_sim(ray_spacing=1e-9), "error",
    "ray_spacing")
scalar_cases("simulate.mesh", lambda v: _mesh_sim(rays_per_bin=v), "rays_per_bin",
             ok=("none",), names=("rays_per_bin", "ray_spacing"))
api("simulate.mesh.rays_per_bin=tiny", lambda: _mesh_sim(rays_per_bin=1e-300), "warn")
api("simulate.mesh.ray_spacing+rays_per_bin", lambda: _mesh_sim(ray_spacing=0.1,
                                                                rays_per_bin=2),
    "error", ("ray_spacing", "rays_per_bin"))
for _key, _v in {"x": "x", "int": 3}.items():
    api(f"simulate.mesh.sampling={_key}", lambda v=_v: _mesh_sim(sampling=v), "error",
        "sampling")
api("simulate.mesh.sampling=regular", lambda: _mesh_sim(sampling="regular"), "ok",
    check=_finite)
api("simulate.mesh.regular+seed", lambda: _mesh_sim(sampling="regular", seed=1), "error",
    "seed")
for _key, _v in {"neg": -1, "float": 0.5, "str": "1", "bool": True, "nan": nan,
                 "list": [1, 2]}.items():
    api(f"simulate.mesh.seed={_key}", lambda v=_v: _mesh_sim(seed=v), "error", "seed")
api("simulate.mesh.seed=huge", lambda: _mesh_sim(seed=2**70), "ok", check=_finite)
api("simulate.mesh.seed=np.int64", lambda: _mesh_sim(seed=np.int64(3)), "ok")
for _key, _v in {"x": "x", "int": 3, "upper": "FLAT"}.items():
    api(f"simulate.mesh.normals={_key}", lambda v=_v: _mesh_sim(normals=v), "error", "normals")
api("simulate.mesh.normals=smooth", lambda: _mesh_sim(normals="smooth"), "ok", check=_finite)
api("simulate.mesh.normals=exact", lambda: _mesh_sim(normals="exact"), "ok", check=_finite)
api("simulate.mesh.normals=exact-without", lambda: ml.simulate(
    _box(material=_dg()), _lad(), model="mesh", normals="exact"), "error", "exact")
api("simulate.mesh.back_faces=x", lambda: _mesh_sim(back_faces="x"), "error", "back_faces")
for _key, _v in {"str": "no", "int": 1}.items():
    api(f"simulate.mesh.footprint={_key}", lambda v=_v: _mesh_sim(footprint=v), "error",
        "footprint")
api("simulate.mesh.footprint=True", lambda: _mesh_sim(footprint=True), "ok", check=_finite)
for _key, _v in {"nan": (nan, 0, 0), "zero": (0, 0, 0), "short": (1, 0), "str": "x",
                 "per-view-count": [(0, 1, 0)] * 3, "opposite": (-1, 0, 0),
                 "inf": (inf, 0, 0)}.items():
    api(f"simulate.mesh.receiver={_key}", lambda v=_v: _mesh_sim(receiver=v), "error",
        "receiver")
api("simulate.mesh.receiver+footprint", lambda: _mesh_sim(receiver=(0, 1, 1),
                                                          footprint=True),
    "error", ("footprint", "receiver"))
# the 320-face sphere has lit faces exactly edge-on to (0, 1, 1): under Eq. 8 their F's
# 1/cos θr made bins of 7e9 (against 5e-3) without a word; now it is said, and received
# power is the finite answer
api("simulate.mesh.receiver-edge-on-warns", lambda: _mesh_sim(receiver=(0, 1, 1)), "warn",
    "receiver")
api("simulate.mesh.receiver", lambda: _mesh_sim(receiver=(0, 1, 1), radiometry="power"),
    "ok", check=_finite)
api("simulate.mesh.receiver-oblique", lambda: _mesh_sim(receiver=(0.3, 0.5, 0.81)), "ok",
    check=_finite)
for _key, _v in {"zero": 0.0, "neg": -0.1, "one": 1.0, "above-1": 1.5, "nan": nan,
                 "str": "x", "bool": True}.items():
    api(f"simulate.mesh.tol={_key}", lambda v=_v: _mesh_sim(tol=v), "error", "tol")
api("simulate.mesh.tol+run_dir", lambda tmp: _mesh_sim(tol=0.5, run_dir=tmp / "run"),
    "error", ("tol", "run_dir"))
api("simulate.mesh.tol+ray_spacing", lambda: _mesh_sim(tol=0.5, ray_spacing=0.1), "error",
    ("tol", "ray_spacing"))
for _key, _v in {"zero": 0, "nan": nan, "str": "x", "neg": -5}.items():
    api(f"simulate.mesh.max_rays={_key}", lambda v=_v: _mesh_sim(tol=0.5, max_rays=v),
        "error", "max_rays")
api("simulate.mesh.max_rays-without-tol", lambda: _mesh_sim(max_rays=1e6), "error",
    "max_rays")
api("simulate.mesh.tol-budget-warns", lambda: _mesh_sim(tol=0.01, max_rays=1), "warn",
    check=_finite)


def _refuses_many_jobs():
    """True when a huge ``jobs`` is refused before any process starts."""
    from meshladar.errors import ParameterError
    from meshladar.stream import _executor

    try:
        ex, own = _executor(10**5, None, 1.0, 1)
    except ParameterError:
        return True
    if own:
        ex.shutdown()
    return False


for _key, _v in {"zero": 0, "neg": -1, "float": 2.5, "str": "2", "bool": True,
                 "nan": nan}.items():
    api(f"simulate.mesh.jobs={_key}", lambda v=_v: _mesh_sim(jobs=v), "error", "jobs")
api("simulate.mesh.jobs=huge", lambda: _mesh_sim(jobs=10**5), "error", "jobs",
    precheck=_refuses_many_jobs)
api("simulate.mesh.jobs=1", lambda: _mesh_sim(jobs=1), "ok", check=_finite)
api("simulate.mesh.executor=str", lambda: _mesh_sim(executor="x"), "error", "executor")
api("simulate.mesh.executor=object", lambda: _mesh_sim(executor=object()), "error",
    "executor")


def _with_threads():
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as ex:
        return _mesh_sim(executor=ex)


api("simulate.mesh.executor=threads", _with_threads, "ok", check=_finite)
for _key, _v in {"str": "yes", "none": None, "int": 1}.items():
    api(f"simulate.mesh.progress={_key}", lambda v=_v: _mesh_sim(progress=v), "error",
        "progress")
for _key, _v in {"int": 123, "empty": "", "list": ["run"]}.items():
    api(f"simulate.mesh.run_dir={_key}", lambda v=_v: _mesh_sim(run_dir=v), "error", "run_dir")
api("simulate.mesh.run_dir=file", lambda tmp: _mesh_sim(run_dir=tmp / "f.txt"), "error",
    ("run_dir", "f.txt"), setup=files({"f.txt": b"x"}))
api("simulate.mesh.run_dir=missing-parents", lambda tmp: _mesh_sim(run_dir=tmp / "a" / "b"),
    "ok", check=_finite)
api("simulate.mesh.run_dir=read-only", lambda tmp: _mesh_sim(run_dir=tmp / "ro" / "run"),
    "error", ("run_dir", "/ro"), setup=files({"ro": _read_only}), skip_root=True)

# ------------------------------------------------------------------ trace and weigh
api("trace.scene=str", lambda: ml.trace("x", _lad()), "error", "scene")
api("trace.ladar=str", lambda: ml.trace(_sphere(), "ladar"), "error", "ladar")
api("trace.analytic-scene", lambda: ml.trace(_disk(), _lad()), "error", "mesh")
api("trace.mode=x", lambda: ml.trace(_sphere(), _lad(), mode="x"), "error", "mode")
api("trace.normals=x", lambda: ml.trace(_sphere(), _lad(), normals="x"), "error", "normals")
api("trace.receiver=nan", lambda: ml.trace(_sphere(), _lad(), receiver=(nan, 0, 0)), "error",
    "receiver")
api("trace.jobs=0", lambda: ml.trace(_sphere(), _lad(), jobs=0), "error", "jobs")
api("trace.seed=-1", lambda: ml.trace(_sphere(), _lad(), seed=-1), "error", "seed")
api("trace.ray_spacing=nan", lambda: ml.trace(_sphere(), _lad(), ray_spacing=nan), "error",
    "ray_spacing")
api("trace.ok", lambda: ml.trace(_sphere(), _lad()), "ok",
    check=lambda h: h.rays.sum() > 0)
api("weigh.hits=str", lambda: ml.weigh("hits"), "error", "hits")
api("weigh.hits=None", lambda: ml.weigh(None), "error", "hits")
api("weigh.materials=[str]", lambda: ml.weigh(_hits(), ["x"]), "error", "materials[0]")
api("weigh.materials=str", lambda: ml.weigh(_hits(), "dark_gray"), "error", "materials")
api("weigh.materials=two", lambda: ml.weigh(_hits(), [_dg(), _al()]), "error", "materials")
api("weigh.materials=[]", lambda: ml.weigh(_hits(), []), "error", "materials")
api("weigh.materials=one", lambda: ml.weigh(_hits(), _al()), "ok", check=_finite)
api("weigh.footprint=str", lambda: ml.weigh(_hits(), footprint="no"), "error", "footprint")
for _key, _v in {"nan": [0.0, nan], "decreasing": [1.0, 0.0], "one": [0.0], "str": "x",
                 "2d": [[0.0, 1.0]], "inf": [-inf, 0.0], "empty": []}.items():
    api(f"weigh.bin_edges={_key}", lambda v=_v: ml.weigh(_hits(), bin_edges=v), "error",
        "bin_edges")
api("weigh.bin_edges=other", lambda: ml.weigh(_hits(), bin_edges=np.linspace(-1, 1, 5)),
    "ok", check=lambda s: s.n_bins == 4 and _finite(s))

# ------------------------------------------------------------------ sinograms
_ANG = [0.0, 90.0]
_E4 = np.linspace(-1, 1, 5)
for _key, _v in {"nan": [[nan, 0, 0, 0], [0, 0, 0, 0]], "inf": [[inf, 0, 0, 0]] * 2,
                 "1d": [1.0, 2.0], "3d": np.ones((2, 4, 1)), "str": "x", "none": None,
                 "ragged": [[1.0], [1.0, 2.0]], "empty": np.zeros((0, 4))}.items():
    api(f"Sinogram.values={_key}", lambda v=_v: ml.Sinogram(v, angles_deg=_ANG, bin_edges=_E4),
        "error", "values")
for _key, _v in {"short": [0.0], "nan": [0.0, nan], "none": None, "str": "x",
                 "2d": [[0.0, 90.0]]}.items():
    api(f"Sinogram.angles_deg={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=v,
                                                                bin_edges=_E4),
        "error", "angles_deg")
for _key, _v in {"short": [0.0, 1.0], "decreasing": _E4[::-1], "nan": [0, nan, 1, 2, 3],
                 "none": None, "str": "x"}.items():
    api(f"Sinogram.bin_edges={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG,
                                                               bin_edges=v),
        "error", "bin_edges")
for _key, _v in {"shape": [[1, 0, 0]], "nan": [[nan, 0, 0], [0, 1, 0]],
                 "zero": [[0, 0, 0], [0, 1, 0]]}.items():
    api(f"Sinogram.view_vectors={_key}", lambda v=_v: ml.Sinogram(
        np.ones((2, 4)), angles_deg=_ANG, bin_edges=_E4, view_vectors=v), "error",
        "view_vectors")
for _key, _v in {"str": "x", "none": None, "list": [1, 2]}.items():
    api(f"Sinogram.info={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG,
                                                          bin_edges=_E4, info=v),
        "error", "info")
api("Sinogram.model=int", lambda: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG, bin_edges=_E4,
                                              model=3), "error", "model")
api("Sinogram.negative-values", lambda: ml.Sinogram(-np.ones((2, 4)), angles_deg=_ANG,
                                                    bin_edges=_E4), "ok",
    check=lambda s: s.values.min() == -1)
api("Sinogram.int-values", lambda: ml.Sinogram(np.ones((2, 4), int), angles_deg=_ANG,
                                               bin_edges=_E4), "ok",
    check=lambda s: s.values.dtype == np.float64)

# ------------------------------------------------------------------ reconstruction
for _key, _v in dict(COUNTS, huge=10**5).items():
    api(f"fbp.size={_key}", lambda v=_v: ml.fbp(_sino(), size=v), "error", "size")
api("fbp.size=1", lambda: ml.fbp(_sino(), size=1), "ok", check=lambda im: im.values.shape
    == (1, 1))
scalar_cases("fbp", lambda v: ml.fbp(_sino(), size=8, extent=v), "extent", ok=("huge",),
             checks={"huge": _finite})
for _key, _v in {"x": "x", "none": None, "upper": "RAMP"}.items():
    api(f"fbp.filter={_key}", lambda v=_v: ml.fbp(_sino(), size=8, filter=v), "error", "filter")
api("fbp.interpolation=cubic", lambda: ml.fbp(_sino(), size=8, interpolation="cubic"), "error",
    "interpolation")
for _key, _v in {"nan": (nan, 0.0), "short": (0.0,), "str": "x", "none": None,
                 "inf": (0.0, inf)}.items():
    api(f"fbp.center={_key}", lambda v=_v: ml.fbp(_sino(), size=8, center=v), "error", "center")
api("fbp.sinogram=str", lambda: ml.fbp("x"), "error", "sinogram")
api("fbp.sinogram=array", lambda: ml.fbp(np.ones((32, 8))), "error", "sinogram")
api("fbp.off-plane", lambda: ml.fbp(ml.Sinogram(np.ones((1, 4)), angles_deg=[0.0],
                                                bin_edges=_E4, view_vectors=[[0, 0, 1]])),
    "error", "view")
api("fbp.one-view-warns", lambda: ml.fbp(ml.Sinogram(np.ones((1, 4)), angles_deg=[0.0],
                                                     bin_edges=_E4), size=8), "warn")
api("fbp.gap-warns", lambda: ml.fbp(ml.Sinogram(np.ones((3, 4)), angles_deg=[0.0, 10.0, 20.0],
                                                bin_edges=_E4), size=8), "warn")
def _uniform_sino(value):
    return ml.Sinogram(np.full((32, 8), value), angles_deg=np.arange(32) * 360.0 / 32,
                       bin_edges=np.linspace(-1, 1, 9))


api("fbp.values=1e-300", lambda: ml.fbp(_uniform_sino(1e-300), size=8), "ok",
    check=lambda im: _finite(im) and im.values.max() > 0)
api("fbp.values=1e307", lambda: ml.fbp(_uniform_sino(1e307), size=8), "ok", check=_finite)
api("fbp.values=1.7e308", lambda: ml.fbp(_uniform_sino(1.7e308), size=8), "error",
    ("values", "sinogram"))
api("log_radiance.values=1.7e308", lambda: ml.log_radiance(_uniform_sino(1.7e308)), "ok",
    check=_finite)
api("fbp.non-uniform-bins", lambda: ml.fbp(ml.Sinogram(
    np.ones((32, 4)), angles_deg=np.arange(32) * 360.0 / 32, bin_edges=[-1, -0.5, 0, 0.2, 1]),
    size=8),
    "ok", check=lambda im: im.info["resampled"] and _finite(im))

scalar_cases("log_radiance", lambda v: ml.log_radiance(_sino(), floor=v), "floor")
api("log_radiance.sinogram=str", lambda: ml.log_radiance("x"), "error", "sinogram")
api("log_radiance.sinogram=array", lambda: ml.log_radiance(np.ones((2, 2))), "error",
    "sinogram")
api("log_radiance.all-zero", lambda: ml.log_radiance(ml.Sinogram(
    np.zeros((2, 4)), angles_deg=_ANG, bin_edges=_E4)), "ok",
    check=lambda s: not s.values.any())
scalar_cases("clip_radiance", lambda v: ml.clip_radiance(_sino(), threshold=v), "threshold")
api("clip_radiance.sinogram=str", lambda: ml.clip_radiance("x"), "error", "sinogram")
api("clip_radiance.threshold=1", lambda: ml.clip_radiance(_sino(), threshold=1.0), "ok",
    check=lambda s: np.array_equal(s.values, _sino().values))


def _resample(*args, **kw):
    from meshladar.reconstruct import resample_uniform

    return resample_uniform(*args, **kw)


for _key, _v in COUNTS.items():
    if _key != "none":
        api(f"resample_uniform.n_bins={_key}", lambda v=_v: _resample(_sino(), v), "error",
            ("n_bins must", "n_bins:"))
api("resample_uniform.n_bins=None", lambda: _resample(_sino(), None), "ok",
    check=lambda s: s.n_bins == 8)
api("resample_uniform.sino=str", lambda: _resample("x"), "error", "sino")

# ------------------------------------------------------------------ result files


def _load(path):
    return ml.io.load_result(path)


_file_cases("io.load_result", "api", _load, ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_result, "text": b"hello\n", "not-utf8": NOT_UTF8_TOML,
             "no-meta": _no_meta_result, "pickled": _pickled_result,
             "deep-meta": _deep_meta_result}, ("bad.npz",))
_file_cases("io.load_result", "api", _load, ".dat", {"result": _result}, (), expect="ok")
api("io.load_result.None", lambda: ml.io.load_result(None), "error", ("path", "None"))
api("io.load_result.int", lambda: ml.io.load_result(3), "error", ("path", "3"))
_file_cases("io.load_sinogram", "api", lambda p: ml.io.load_sinogram(p), ".npz", {"image": _image_result, "no-meta": _no_meta_result}, ("bad.npz",))
api("io.save_result.path=empty", lambda: ml.io.save_result("", {"a": np.ones(2)}, {}), "error",
    "path")
api("io.save_result.path=dir", lambda tmp: ml.io.save_result(tmp, {"a": np.ones(2)}, {}),
    "error", ("path", "folder", "directory"))
api("io.save_result.path=None", lambda: ml.io.save_result(None, {"a": np.ones(2)}, {}),
    "error", "path")
api("io.save_result.missing-folder", lambda tmp: ml.io.save_result(tmp / "a" / "r.npz",
                                                                   {"a": np.ones(2)}, {}),
    "ok")
api("io.save_result.object-array", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"a": np.array([{}], dtype=object)}, {}), "error", ("a", "array"))
api("io.save_result.meta-not-json", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"a": np.ones(2)}, {"x": object()}), "error", "meta")
api("io.save_result.reserved-key", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"__meta__": np.ones(2)}, {}), "error", "__meta__")
api("io.save_result.arrays=str", lambda tmp: ml.io.save_result(tmp / "r.npz", "x", {}),
    "error", "arrays")
api("io.save_result.meta=str", lambda tmp: ml.io.save_result(tmp / "r.npz", {}, "x"),
    "error", "meta")
api("io.save_result.read-only", lambda tmp: ml.io.save_result(tmp / "ro" / "r.npz",
                                                              {"a": np.ones(2)}, {}),
    "error", "/ro", setup=files({"ro": _read_only}), skip_root=True)
api("io.save_sinogram.sino=str", lambda tmp: ml.io.save_sinogram(tmp / "r.npz", "x"), "error",
    "sino")

# ------------------------------------------------------------------ coating tables


def _table(path):
    return ml.materials.load_table(path)


_file_cases("materials.load_table", "api", _table, ".toml",
            dict(BAD_TOML, **{
                "long-int": b"[m]\nrho_d = " + b"9" * 5000 + b"\n",
                "unknown-field": TABLE + b"colour = 1\n",
                "string-field": TABLE.replace(b"0.1\ne", b"\"0.1\"\ne"),
                "nan-field": TABLE.replace(b"rho_d = 0.1", b"rho_d = nan"),
                "bool-field": TABLE.replace(b"rho_d = 0.1", b"rho_d = true"),
                "lobes": TABLE + b"lobes = \"x\"\n",
                "not-a-table": b"x = [1]\n",
                "missing-field": b"[m]\nrho_d = 0.1\n",
                "energy": TABLE.replace(b"epsilon = 0.5", b"epsilon = 0.99")}), ("bad.toml",))
_file_cases("materials.load_table", "api", _table, ".txt", {"valid": TABLE}, (), expect="ok",
            check=lambda t: "mine" in t)
api("materials.load_table.None", lambda: ml.materials.load_table(None), "error", "path")
api("materials.parse_table.str", lambda: ml.materials.parse_table("x"), "error", "table")
api("materials.parse_table.empty", lambda: ml.materials.parse_table({}), "error", "table")
api("materials.parse_table.entry-int", lambda: ml.materials.parse_table({"a": 1}), "error",
    "[a]")

# ------------------------------------------------------------------ phantom specs


def _phantom(path, **kw):
    return ml.phantoms.load(path, **kw)


_file_cases("phantoms.load", "api", _phantom, ".toml", dict(BAD_TOML, **{
    "long-int": LONG_INT_TOML,
    "no-shapes": b"[ladar]\nn_bins = 8\n",
    "shape-not-table": b"shape = 3\n",
    "unknown-kind": _spec(kind='"square"'),
    "missing-radius": DISK_SPEC.replace(b"radius = 0.5\n", b""),
    "radius-nan": _spec(radius="nan"),
    "radius-bool": _spec(radius="true"),
    "radius-neg": _spec(radius="-1"),
    "center-short": _spec(center="[0]"),
    "material-unknown": _spec(material='"unobtainium"'),
    "material-int": _spec(material="3"),
    "n_bins-zero": _spec(n_bins="0"),
    "n_bins-float": _spec(n_bins="1e10"),
    "n_bins-huge": _spec(n_bins="10000000000"),
    "bin_width-neg": _spec(bin_width="-1"),
    "step-zero": _spec(angles_deg="{ start = 0.0, stop = 360.0, step = 0.0 }"),
    "step-nan": _spec(angles_deg="{ start = 0.0, stop = 360.0, step = nan }"),
    "stop-inf": _spec(angles_deg="{ start = 0.0, stop = inf, step = 1.0 }"),
    "step-str": _spec(angles_deg='{ start = 0.0, stop = 360.0, step = "1" }'),
    "angles-str": _spec(angles_deg='["a", "b"]'),
    "angles-empty": _spec(angles_deg="[]"),
    "bin_edges-decreasing": DISK_SPEC.replace(b"n_bins = 16\nbin_width = 0.1\n",
                                              b"bin_edges = [1.0, 0.0]\n"),
    "overlap": DISK_SPEC + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):],
    "ladar-not-table": b"ladar = 3\n" + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):],
}), ("bad.toml",))
_file_cases("phantoms.load", "api", _phantom, ".toml", {"valid": DISK_SPEC}, (), expect="ok",
            check=lambda ph: ph.ladar.n_bins == 16 and ph.ladar.n_views == 4)
api("phantoms.load.unknown-name", lambda: ml.phantoms.load("nope"), "error", "nope")
api("phantoms.load.None", lambda: ml.phantoms.load(None), "error", ("name", "path"))
api("phantoms.load.int", lambda: ml.phantoms.load(3), "error", ("name", "path"))
api("phantoms.load.materials=unknown-shape", lambda: ml.phantoms.load(
    "disk_pair", materials={"nope": "dark_gray"}), "error", "nope")
api("phantoms.load.materials=unknown-coating", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": "unobtainium"}), "error", "unobtainium")
api("phantoms.load.materials=str", lambda: ml.phantoms.load("disk_pair",
                                                            materials="dark_gray"),
    "error", "materials")
api("phantoms.load.materials=inline-bad", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": {"rho_d": 2.0}}), "error", ("rho_d", "small"))
api("phantoms.load.materials=coating", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": _al()}), "ok",
    check=lambda ph: _al() in ph.scene.materials)

# ------------------------------------------------------------------ studies (refused before
# any work is done)


def _study(**kw):
    from meshladar import studies

    return studies.faceting_study(**kw)


api("studies.study_scene.phantom", lambda: ml.studies.study_scene("x", "dark_gray"), "error",
    "phantom")
api("studies.study_scene.coating", lambda: ml.studies.study_scene("disk", "x"), "error",
    "coating")
api("studies.faceting_study.setting", lambda: _study(setting="x"), "error", "setting")
api("studies.faceting_study.phantoms", lambda: _study(phantoms=["nope"]), "error",
    ("phantom", "nope"))
api("studies.faceting_study.phantoms=str", lambda: _study(phantoms="disk"), "error",
    "phantoms")
api("studies.faceting_study.coatings", lambda: _study(coatings=["nope"]), "error",
    ("coating", "nope"))
api("studies.faceting_study.run_dir=int", lambda: _study(run_dir=123), "error", "run_dir",
    forbid=("meshladar.forward:simulate",))
api("studies.faceting_study.executor=str", lambda: _study(executor="x", phantoms=["disk"]),
    "error", "executor")
api("studies.save_study.result=str", lambda tmp: ml.studies.save_study("x", tmp / "s"),
    "error", "result")

# ------------------------------------------------------------------ the viewer (off screen;
# the bad arguments are refused before anything is drawn)


def _viewer():
    from meshladar.viz import viewer

    return viewer


def _show(**kw):
    return _viewer().show_scene(_disk(), off_screen=True, **kw)


for _key, _v in {"nan": nan, "inf": inf, "str": "x", "list": [1, 2]}.items():
    api(f"viewer.show_scene.view_angle_deg={_key}", lambda v=_v: _show(view_angle_deg=v),
        "error", "view_angle_deg")
for _key, _v in {"zero": (0, 0, 0), "nan": (nan, 0, 0), "short": (1, 0), "str": "x"}.items():
    api(f"viewer.show_scene.view_vector={_key}", lambda v=_v: _show(view_vector=v), "error",
        "view_vector")
api("viewer.show_scene.segments=2", lambda: _show(segments=2), "error", "segments")
api("viewer.show_scene.iso_ranges=-1", lambda: _show(iso_ranges=-1), "error", "iso_ranges")
api("viewer.show_scene.window_size=0", lambda: _show(window_size=(0, 0)), "error",
    "window_size")
api("viewer.show_scene.scene=str", lambda: _viewer().show_scene("disk", off_screen=True),
    "error", "scene")

# ================================================================== the command line

#: What the long commands run: a bad argument must never reach it.
_WORK = ("meshladar.studies.paper:simulate", "meshladar.forward:simulate",
         "meshladar.cli.simulate:simulate", "meshladar.studies.bench:bench_analytic")

_SIM = ["simulate", "disk", "-o", "{tmp}/r.npz", "--quiet", "--views", "4"]
_MESH = ["simulate", "{tmp}/sphere.stl", "-o", "{tmp}/r.npz", "--quiet", "--views", "2",
         "--bins", "8"]
_SPHERE_FILE = files({"sphere.stl": _stl})
_REC = ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.png", "--quiet", "--size", "16"]
_RESULT_FILE = files({"r.npz": _result})


def _wrote(name):
    return lambda tmp: (tmp / name).is_file() and (tmp / name).stat().st_size > 0


def _flag_names(flag):
    return (flag, flag.lstrip("-").replace("-", "_"))


# ------------------------------------------------------------------ top level
cli("top.no-command", [], "error", "COMMAND")
cli("top.unknown-command", ["nope"], "error", "nope")
cli("top.unknown-option", ["--bogus", "demo"], "error", "--bogus")
cli("top.version", ["--version"], "ok")
for _argv in (["demo"], ["materials"], ["paper", "{tmp}/out"],
              ["simulate", "disk", "-o", "{tmp}/r.npz"], ["reconstruct", "{tmp}/r.npz", "-o",
                                                          "{tmp}/r.png"],
              ["view", "disk"], ["study", "faceting", "{tmp}/s"], ["bench"]):
    cli(f"{_argv[0]}.help", [_argv[0], "--help"], "ok")
    cli(f"{_argv[0]}.unknown-option", _argv + ["--bogus"], "error", "--bogus",
        forbid=_WORK)

# ------------------------------------------------------------------ demo
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": "", "commas": ",,",
                 "huge": "1e400", "hex": "0x10", "minus-inf": "0,-inf"}.items():
    cli(f"demo.--angles-deg={_key}", ["demo", "--angles-deg", _v], "error", "--angles-deg")
for _key, _v in {"neg": "-30", "zero": "0", "big": "1e300", "gaps": "0,,5",
                 "space": " 5 , 10 "}.items():
    cli(f"demo.--angles-deg={_key}", ["demo", f"--angles-deg={_v}"], "ok")

# ------------------------------------------------------------------ materials
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".toml", BAD_TOML,
            ("bad.toml",))
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".toml",
            {"energy": TABLE.replace(b"epsilon = 0.5", b"epsilon = 0.99")}, ("bad.toml",))
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".txt", {"valid": TABLE}, (),
            expect="ok")
cli("materials.packaged", ["materials"], "ok")
cli("materials.two-tables", ["materials", "a.toml", "b.toml"], "error", "b.toml")

# ------------------------------------------------------------------ paper, study, bench:
# only bad arguments, which must be refused before any work (the work raises if reached)
_PAPER = ("meshladar.studies.paper:simulate",)
_STUDY = ("meshladar.studies.faceting:simulate", "meshladar.forward:simulate")
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "nan": "nan",
                 "empty": ""}.items():
    cli(f"paper.--size={_key}", ["paper", "{tmp}/out", "--size", _v], "error", "--size",
        forbid=_PAPER)
cli("paper.--size=huge", ["paper", "{tmp}/out", "--size", "100000"], "error", "size",
    forbid=_PAPER)
cli("paper.outdir=file", ["paper", "{tmp}/f.txt"], "error", "f.txt",
    setup=files({"f.txt": b"x"}), forbid=_PAPER)
cli("paper.outdir=empty", ["paper", ""], "error", ("outdir", "''"), forbid=_PAPER)
cli("paper.outdir=read-only", ["paper", "{tmp}/ro/out"], "error", "/ro",
    setup=files({"ro": _read_only}), skip_root=True, forbid=_PAPER)
cli("paper.no-outdir", ["paper"], "error", "outdir")
cli("study.kind", ["study", "nope", "{tmp}/s"], "error", "nope")
cli("study.no-outdir", ["study", "faceting"], "error", "outdir")
cli("study.outdir=file", ["study", "faceting", "{tmp}/f.txt", "--quiet"], "error", "f.txt",
    setup=files({"f.txt": b"x"}), forbid=_STUDY)
cli("study.outdir=empty", ["study", "faceting", "", "--quiet"], "error", ("outdir", "''"),
    forbid=_STUDY)
cli("study.outdir=read-only", ["study", "faceting", "{tmp}/ro/s", "--quiet"], "error", "/ro",
    setup=files({"ro": _read_only}), skip_root=True, forbid=_STUDY)
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"bench.--repeats={_key}", ["bench", "--repeats", _v], "error", "--repeats",
        forbid=_WORK)

# ------------------------------------------------------------------ simulate: options
_INT_BAD = {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "nan": "nan", "empty": "",
            "huge-exp": "1e400"}
_POS_BAD = {"zero": "0", "neg": "-1", "str": "x", "nan": "nan", "inf": "inf", "empty": "",
            "huge-exp": "1e400"}
_FEW = ("zero", "str", "nan", "empty")      # for options whose parser another shares
for _flag in ("--views", "--bins", "--segments", "--view-vectors", "--jobs", "--workers"):
    for _key, _v in _INT_BAD.items():
        if _flag == "--views" or _key in _FEW:
            cli(f"simulate.{_flag}={_key}", _SIM[:-2] + [_flag, _v], "error", _flag)
for _flag in ("--bin-width", "--ray-spacing", "--rays-per-bin", "--tol", "--max-rays",
              "--pixel-size"):
    for _key, _v in _POS_BAD.items():
        if _flag in ("--bin-width", "--ray-spacing") or _key in _FEW + ("neg", "inf"):
            cli(f"simulate.{_flag}={_key}", _SIM + [_flag, _v], "error", _flag)
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": ""}.items():
    cli(f"simulate.--z0={_key}", _SIM + ["--z0", _v], "error", "--z0")
for _key, _v in {"neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"simulate.--seed={_key}", _MESH + ["--seed", _v], "error", "--seed")
for _key, _v in {"two": "1,0", "zero": "0,0,0", "nan": "nan,0,0", "str": "x", "empty": "",
                 "four": "1,0,0,0", "inf": "inf,0,0"}.items():
    cli(f"simulate.--receiver={_key}", _MESH + [f"--receiver={_v}"], "error", "--receiver")
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": "", "commas": ","}.items():
    cli(f"simulate.--angles-deg={_key}", _SIM[:-2] + ["--angles-deg", _v], "error",
        "--angles-deg")
for _flag, _v in (("--model", "x"), ("--mode", "x"), ("--normals", "x"),
                  ("--sampling", "x")):
    cli(f"simulate.{_flag}=x", _SIM + [_flag, _v], "error", _flag)
cli("simulate.--scheduler=not-an-address", _MESH + ["--scheduler", "nonsense"], "error",
    ("--scheduler", "scheduler"), setup=_SPHERE_FILE)

# values argparse accepts that the run must refuse (up front, before any work)
cli("simulate.--views=huge", _SIM[:-2] + ["--views", "1000000000"], "error",
    _flag_names("--views") + ("views",))
cli("simulate.--view-vectors=huge", _MESH[:-4] + ["--bins", "8", "--view-vectors",
                                                  "1000000000"], "error",
    _flag_names("--view-vectors") + ("views",), setup=_SPHERE_FILE)
cli("simulate.--bins=huge", _SIM + ["--bins", "10000000000"], "error",
    _flag_names("--bins") + ("bins",))
cli("simulate.--bin-width=tiny", _SIM + ["--bin-width", "1e-12"], "error",
    _flag_names("--bin-width"))
cli("simulate.--bin-width=huge", _SIM + ["--bin-width", "1e300"], "ok", check=_wrote("r.npz"))
cli("simulate.--segments=huge", _SIM + ["--model", "mesh", "--segments", "100000000"], "error",
    _flag_names("--segments"))
cli("simulate.--ray-spacing=tiny", _MESH + ["--ray-spacing", "1e-9"], "error",
    _flag_names("--ray-spacing"), setup=_SPHERE_FILE)
cli("simulate.--ray-spacing=huge", _MESH + ["--ray-spacing", "1e300"], "warn",
    setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.--rays-per-bin=huge", _MESH + ["--rays-per-bin", "1e300"], "error",
    _flag_names("--rays-per-bin") + ("ray_spacing",), setup=_SPHERE_FILE)
cli("simulate.--tol=1", _MESH + ["--tol", "1"], "error", _flag_names("--tol"),
    setup=_SPHERE_FILE)
cli("simulate.--tol=2", _MESH + ["--tol", "2"], "error", _flag_names("--tol"),
    setup=_SPHERE_FILE)
cli("simulate.--max-rays=0.5", _MESH + ["--tol", "0.5", "--max-rays", "0.5"], "error",
    _flag_names("--max-rays"), setup=_SPHERE_FILE)
cli("simulate.--pixel-size=huge", _SIM + ["--model", "pixel", "--pixel-size", "1e9"],
    "error", _flag_names("--pixel-size"))
cli("simulate.--pixel-size=tiny", _SIM + ["--model", "pixel", "--pixel-size", "1e-9"],
    "error", _flag_names("--pixel-size"))
cli("simulate.--jobs=huge", _MESH + ["--jobs", "100000"], "error", _flag_names("--jobs"),
    setup=_SPHERE_FILE, precheck=_refuses_many_jobs)
cli("simulate.--receiver=opposite", _MESH + ["--receiver=-1,0,0"], "error",
    _flag_names("--receiver"), setup=_SPHERE_FILE)
cli("simulate.--z0=outside-warns", _MESH + ["--mode", "slice", "--z0", "5"], "warn",
    setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.--seed=huge", _MESH + ["--seed", "1" + "0" * 30], "ok", setup=_SPHERE_FILE,
    check=_wrote("r.npz"))

# options that do not apply, or clash
cli("simulate.--views+--angles-deg", _SIM + ["--angles-deg", "0,90"], "error",
    ("--views", "--angles-deg"))
cli("simulate.analytic+--jobs", _SIM + ["--jobs", "2"], "ok", check=_wrote("r.npz"))
cli("simulate.analytic+--mode", _SIM + ["--mode", "3d"], "error", "--mode")
cli("simulate.analytic+--backend", _SIM + ["--backend", "packets"], "error", "--backend")
cli("simulate.--backend=optix", _MESH + ["--backend", "optix"], "error", "--backend",
    setup=_SPHERE_FILE)
cli("simulate.--backend=embreex", _MESH + ["--backend", "embreex"], "ok", setup=_SPHERE_FILE,
    check=_wrote("r.npz"))
cli("simulate.analytic+--pixel-size", _SIM + ["--pixel-size", "0.01"], "error",
    "--pixel-size")
cli("simulate.analytic+--scheduler", _SIM + ["--scheduler", "nonsense"], "error",
    ("--scheduler", "scheduler"))
cli("simulate.analytic+--view-vectors", _SIM[:-2] + ["--view-vectors", "10"], "error",
    ("--view-vectors", "view"))
cli("simulate.mesh+--segments", _MESH + ["--segments", "64"], "error", "--segments",
    setup=_SPHERE_FILE)
cli("simulate.--seed+regular", _MESH + ["--seed", "1", "--sampling", "regular"], "error",
    "--seed", setup=_SPHERE_FILE)
cli("simulate.--z0+3d", _MESH + ["--z0", "0.1", "--mode", "3d"], "error", "--z0",
    setup=_SPHERE_FILE)
cli("simulate.--max-rays-without-tol", _MESH + ["--max-rays", "1e6"], "error", "--max-rays",
    setup=_SPHERE_FILE)
cli("simulate.--jobs+--workers", _MESH + ["--jobs", "1", "--workers", "2"], "error",
    ("--jobs", "--workers"), setup=_SPHERE_FILE)
cli("simulate.--receiver+--footprint", _MESH + ["--receiver", "0,1,1", "--footprint"],
    "error", ("--footprint", "footprint"), setup=_SPHERE_FILE)
cli("simulate.--tol+--run-dir", _MESH + ["--tol", "0.5", "--run-dir", "{tmp}/run"], "error",
    ("--tol", "run_dir", "--run-dir"), setup=_SPHERE_FILE)
cli("simulate.--tol+--ray-spacing", _MESH + ["--tol", "0.5", "--ray-spacing", "0.1"], "error",
    ("--tol", "tol"), setup=_SPHERE_FILE)

# coatings
for _key, _v in {"no-equals": "small", "unknown-coating": "small=unobtainium",
                 "unknown-shape": "nope=dark_gray", "empty-name": "=dark_gray"}.items():
    cli(f"simulate.--coating={_key}", ["simulate", "disk_pair", "-o", "{tmp}/r.npz", "--quiet",
                                       "--views", "4", "--coating", _v], "error",
        ("--coating", "coating", "small", "nope", "unobtainium", "''"))
cli("simulate.--material-of-phantom", _SIM + ["--material", "aluminum"], "error", "--material")
cli("simulate.--material=unknown", _MESH + ["--material", "unobtainium"], "error",
    "unobtainium", setup=_SPHERE_FILE)
cli("simulate.--coating=unknown-part", _MESH + ["--coating", "nope=aluminum"], "error",
    "nope", setup=_SPHERE_FILE)
_file_cases("simulate.--materials", "cli", lambda p: _SIM + ["--materials", p], ".toml",
            {k: BAD_TOML[k] for k in ("missing", "dir", "junk", "not-utf8", "deep")},
            ("bad.toml",))
cli("simulate.--materials=valid", ["simulate", "disk_pair", "-o", "{tmp}/r.npz", "--quiet",
                                   "--views", "4", "--materials", "{tmp}/t.toml",
                                   "--coating", "small=mine"], "ok",
    setup=files({"t.toml": TABLE}), check=_wrote("r.npz"))

# ------------------------------------------------------------------ simulate: the scene
cli("simulate.scene=unknown", ["simulate", "nope", "-o", "{tmp}/r.npz"], "error", "nope")
_file_cases("simulate.spec", "cli", lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet"],
            ".toml", dict(BAD_TOML, **{"long-int": LONG_INT_TOML,
                                       "radius-nan": _spec(radius="nan"),
                                       "overlap": DISK_SPEC
                                       + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):]}),
            ("bad.toml",))
_file_cases("simulate.mesh-file.stl", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2"], ".stl",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("simulate.mesh-file.obj", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2"], ".obj",
            {"junk": JUNK, "not-utf8": NOT_UTF8_OBJ, "text": b"hello world\n"}, ("bad.obj",))
_file_cases("simulate.mesh-file", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2",
                       "--bins", "8"], ".dat", {"binary-stl": _stl}, (), expect="ok",
            check=_wrote("r.npz"))
_file_cases("simulate.mesh-file", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet"], ".npz",
            {"result": _result}, ("bad.npz",))
cli("simulate.spec=valid", ["simulate", "{tmp}/s.toml", "-o", "{tmp}/r.npz", "--quiet"], "ok",
    setup=files({"s.toml": DISK_SPEC}), check=_wrote("r.npz"))
cli("simulate.mesh", _MESH, "ok", setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.phantom-as-mesh", _SIM + ["--model", "mesh", "--segments", "64", "--bins", "8"],
    "ok", check=_wrote("r.npz"))
cli("simulate.pixel", _SIM + ["--model", "pixel", "--bins", "16"], "ok", check=_wrote("r.npz"))

# ------------------------------------------------------------------ simulate: the output
cli("simulate.-o=empty", ["simulate", "disk", "-o", "", "--quiet"], "error", "-o")
cli("simulate.-o=dir", ["simulate", "disk", "-o", "{tmp}", "--quiet"], "error", "-o")
cli("simulate.-o=dot", ["simulate", "disk", "-o", ".", "--quiet"], "error", "-o")
cli("simulate.-o=txt", ["simulate", "disk", "-o", "{tmp}/r.txt", "--quiet"], "error", "-o")
cli("simulate.-o=no-suffix", ["simulate", "disk", "-o", "{tmp}/r", "--quiet"], "error", "-o")
cli("simulate.-o=input", ["simulate", "{tmp}/s.toml", "-o", "{tmp}/s.toml", "--quiet"],
    "error", "s.toml", setup=files({"s.toml": DISK_SPEC}))
cli("simulate.-o=input-mesh", ["simulate", "{tmp}/m.npz", "-o", "{tmp}/m.npz", "--quiet"],
    "error", "m.npz", setup=files({"m.npz": _result}))
cli("simulate.-o=--materials", ["simulate", "disk", "-o", "{tmp}/t.npz", "--materials",
                                "{tmp}/t.npz"], "error", "t.npz",
    setup=files({"t.npz": TABLE}))
cli("simulate.-o=--run-dir", _MESH + ["--run-dir", "{tmp}/r.npz"], "error", "r.npz",
    setup=_SPHERE_FILE)
cli("simulate.--run-dir=file", _MESH + ["--run-dir", "{tmp}/f.txt"], "error", "f.txt",
    setup=files({"sphere.stl": _stl, "f.txt": b"x"}))
cli("simulate.--run-dir=empty", _MESH + ["--run-dir", ""], "error", ("--run-dir", "run_dir"),
    setup=_SPHERE_FILE)
cli("simulate.-o=missing-folder", ["simulate", "disk", "-o", "{tmp}/new/sub/r.npz", "--quiet",
                                   "--views", "4"], "ok", check=_wrote("new/sub/r.npz"))
cli("simulate.-o=read-only", ["simulate", "disk", "-o", "{tmp}/ro/r.npz", "--quiet"], "error",
    "/ro", setup=files({"ro": _read_only}), skip_root=True)
cli("simulate.-o=under-a-file", ["simulate", "disk", "-o", "{tmp}/f.txt/r.npz", "--quiet"],
    "error", "f.txt", setup=files({"f.txt": b"x"}))

# ------------------------------------------------------------------ sensor and receive
for _flag in ("--standoff", "--beam-waist", "--pulse-energy", "--aperture", "--wavelength",
              "--flood-radius"):
    for _key in _FEW:
        cli(f"simulate.{_flag}={_key}", _MESH + [_flag, _POS_BAD[_key]], "error", _flag,
            setup=_SPHERE_FILE)
for _flag in ("--extinction", "--beam-divergence"):
    cli(f"simulate.{_flag}=neg", _MESH + [_flag, "-1"], "error", _flag, setup=_SPHERE_FILE)
for _key, _v in {"one": "1", "nan": "nan,0", "str": "x,y"}.items():
    cli(f"simulate.--beam-offset={_key}", _MESH + ["--beam-offset", _v], "error",
        "--beam-offset", setup=_SPHERE_FILE)
cli("simulate.--standoff+analytic", _SIM + ["--standoff", "10"], "error", "--standoff")
cli("simulate.--standoff+slice", _MESH + ["--standoff", "10", "--mode", "slice"], "error",
    "mode='3d'", setup=_SPHERE_FILE)
cli("simulate.--standoff=inside", _MESH + ["--standoff", "0.1"], "error", "inside the target",
    setup=_SPHERE_FILE)
cli("simulate.--beam-divergence-alone", _MESH + ["--beam-divergence", "0.1"], "error",
    "--beam-waist", setup=_SPHERE_FILE)
cli("simulate.--pulse-energy+paper", _MESH + ["--standoff", "50", "--pulse-energy", "1e-3",
                                             "--aperture", "0.1"], "error", "radiometry",
    setup=_SPHERE_FILE)
cli("simulate.--radiometry=x", _SIM + ["--radiometry", "x"], "error", "--radiometry")
_RECV = ["receive", "{tmp}/r.npz", "-o", "{tmp}/w.npz", "--quiet", "--sample-rate", "1e10"]
_file_cases("receive.result", "cli", lambda p: ["receive", p, "-o", "{tmp}/w.npz", "--quiet",
                                                "--sample-rate", "1e10"], ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "pickled": _pickled_result, "image": _image_result}, ("bad.npz",))
cli("receive.ok", _RECV, "ok", setup=_RESULT_FILE, check=_wrote("w.npz"))
for _flag in ("--sample-rate", "--pulse-fwhm", "--realisations", "--speckle-cells"):
    for _key in _FEW:
        cli(f"receive.{_flag}={_key}", _RECV + [_flag, _POS_BAD[_key]], "error", _flag,
            setup=_RESULT_FILE)
cli("receive.--sample-rate=huge", _RECV + ["--sample-rate", "1e18"], "error",
    "sample_rate", setup=_RESULT_FILE)
cli("receive.noise-on-relative-units", _RECV + ["--realisations", "2"], "error",
    "photoelectrons", setup=_RESULT_FILE)
cli("receive.--gain-without-realisations", _RECV + ["--gain", "2"], "error", "--realisations",
    setup=_RESULT_FILE)
cli("receive.--speckle-cells=0.5", _RECV + ["--scale", "10", "--realisations", "2",
                                           "--speckle-cells", "0.5"], "error", "speckle_cells",
    setup=_RESULT_FILE)
cli("receive.-o=input", ["receive", "{tmp}/r.npz", "-o", "{tmp}/r.npz", "--sample-rate",
                         "1e10"], "error", "input", setup=_RESULT_FILE)
cli("receive.--plot=input", _RECV + ["--plot", "{tmp}/r.npz"], "error", "--plot",
    setup=_RESULT_FILE)

# ------------------------------------------------------------------ reconstruct
_file_cases("reconstruct.result", "cli", lambda p: ["reconstruct", p, "-o", "{tmp}/r.png",
                                                    "--quiet", "--size", "16"], ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_result, "text": b"hello\n", "not-utf8": NOT_UTF8_TOML,
             "no-meta": _no_meta_result, "pickled": _pickled_result,
             "deep-meta": _deep_meta_result, "image": _image_result}, ("bad.npz",))
_file_cases("reconstruct.result", "cli", lambda p: ["reconstruct", p, "-o", "{tmp}/r.png",
                                                    "--quiet", "--size", "16"], ".dat",
            {"valid": _result}, (), expect="ok", check=_wrote("r.png"))
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"reconstruct.--size={_key}", _REC[:-1] + [_v], "error", "--size", setup=_RESULT_FILE)
cli("reconstruct.--size=huge", _REC[:-1] + ["100000"], "error", _flag_names("--size"),
    setup=_RESULT_FILE)
for _flag in ("--extent", "--clip"):
    for _key, _v in {"zero": "0", "neg": "-1", "nan": "nan", "inf": "inf", "str": "x"}.items():
        cli(f"reconstruct.{_flag}={_key}", _REC + [_flag, _v], "error", _flag,
            setup=_RESULT_FILE)
cli("reconstruct.--clip=2", _REC + ["--clip", "2"], "error", ("--clip",),
    setup=_RESULT_FILE)
cli("reconstruct.--extent=huge", _REC + ["--extent", "1e300"], "ok", setup=_RESULT_FILE,
    check=_wrote("r.png"))
cli("reconstruct.--filter=x", _REC + ["--filter", "x"], "error", "--filter",
    setup=_RESULT_FILE)
cli("reconstruct.-o=empty", ["reconstruct", "{tmp}/r.npz", "-o", ""], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=dir", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=txt", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.txt"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=npz", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/x.npz"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=input", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.npz"], "error",
    "r.npz", setup=_RESULT_FILE)
cli("reconstruct.-o=image-data-is-input", ["reconstruct", "{tmp}/r.image.npz", "-o",
                                           "{tmp}/r.png"], "error", "r.image.npz",
    setup=files({"r.image.npz": _result}))
cli("reconstruct.-o=missing-folder", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/a/b/r.png",
                                      "--quiet", "--size", "16"], "ok", setup=_RESULT_FILE,
    check=_wrote("a/b/r.png"))
cli("reconstruct.-o=read-only", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/ro/r.png",
                                 "--size", "16"], "error", "/ro",
    setup=files({"r.npz": _result, "ro": _read_only}), skip_root=True)
cli("reconstruct.-o=under-a-file", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/f.txt/r.png",
                                    "--size", "16"], "error", "f.txt",
    setup=files({"r.npz": _result, "f.txt": b"x"}))
cli("reconstruct.no-output", ["reconstruct", "{tmp}/r.npz"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.log+clip", _REC + ["--log", "--clip", "0.5"], "ok", setup=_RESULT_FILE,
    check=_wrote("r.image.npz"))

# ------------------------------------------------------------------ view (bad arguments only)
_VIEW = ["view", "disk", "--screenshot", "{tmp}/v.png", "--quiet"]
for _key, _v in {"nan": "nan", "inf": "inf", "-inf": "-inf", "str": "x", "empty": ""}.items():
    cli(f"view.--view-angle={_key}", _VIEW + [f"--view-angle={_v}"], "error", "--view-angle")
cli("view.--screenshot=empty", ["view", "disk", "--screenshot", ""], "error", "--screenshot")
cli("view.--screenshot=dir", ["view", "disk", "--screenshot", "{tmp}"], "error",
    "--screenshot")
cli("view.--screenshot=jpg", ["view", "disk", "--screenshot", "{tmp}/v.jpg"], "error",
    "--screenshot")
cli("view.--screenshot=input", ["view", "{tmp}/s.png", "--screenshot", "{tmp}/s.png"],
    "error", "--screenshot", setup=files({"s.png": _stl}))
cli("view.no-display", ["view", "disk"], "error", "--screenshot")
cli("view.scene=unknown", ["view", "nope", "--screenshot", "{tmp}/v.png"], "error", "nope")
cli("view.--material-of-phantom", _VIEW + ["--material", "aluminum"], "error", "--material")
cli("view.--coating=unknown", _VIEW + ["--coating", "d=unobtainium"], "error",
    "unobtainium")
_file_cases("view.spec", "cli", lambda p: ["view", p, "--screenshot", "{tmp}/v.png"], ".toml",
            {k: BAD_TOML[k] for k in ("missing", "empty", "junk", "deep")}, ("bad.toml",))
_file_cases("view.mesh-file", "cli", lambda p: ["view", p, "--screenshot", "{tmp}/v.png"],
            ".stl", {"empty": b"", "junk": JUNK, "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("view.--materials", "cli", lambda p: _VIEW + ["--materials", p], ".toml",
            {"junk": JUNK, "not-utf8": NOT_UTF8_TOML, "deep": DEEP_TOML}, ("bad.toml",))

_dups = sorted({c.id for c in CASES if sum(d.id == c.id for d in CASES) > 1})
assert not _dups, f"case ids must be unique: {_dups}"


# ================================================================== running a case

def _takes_tmp(call):
    try:
        return "tmp" in inspect.signature(call).parameters
    except (TypeError, ValueError):
        return False


def _vm_size():
    """This process's address space in bytes (Linux), or None."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


@contextlib.contextmanager
def memory_guard(headroom=GUARD_BYTES):
    """Cap the address space at what is in use plus ``headroom`` while a case runs: an
    allocation the code should have refused becomes a MemoryError, not an OOM."""
    try:
        import resource
    except ImportError:
        yield
        return
    used = _vm_size()
    if used is None:
        yield
        return
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = used + headroom
    for cap in (soft, hard):
        if cap != resource.RLIM_INFINITY:
            limit = min(limit, cap)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _meshladar_warning():
    return getattr(getattr(ml, "errors", None), "MeshladarWarning", Warning)


def _meshladar_error():
    return getattr(getattr(ml, "errors", None), "MeshladarError", ())


def _first_line(text):
    text = str(text).strip()
    return text.splitlines()[0] if text else ""


def _judge_error(case, message):
    """clear or vague, for an error meshladar raised on purpose."""
    one_line = "\n" not in message.strip()
    named = any(n in message for n in case.names) if case.names else True
    return ("clear" if one_line and named else "vague"), message


def _judge_return(case, value, caught):
    warned = [w for w in caught if issubclass(w.category, _meshladar_warning())]
    outcome = "warned" if warned else "accepted"
    message = _first_line(warned[0].message) if warned else ""
    if case.check is not None and case.expect != "error":
        try:
            good = bool(case.check(value))
        except Exception as exc:  # noqa: BLE001 - a failed check is a wrong value
            good, message = False, f"check raised {type(exc).__name__}: {exc}"
        if not good:
            return "wrong", message or f"value check failed: {_first_line(repr(value))[:160]}"
    return outcome, message


def _run_api(case, tmp):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            value = case.call(tmp) if _takes_tmp(case.call) else case.call()
        except _meshladar_error() as exc:
            return _judge_error(case, str(exc))
        except Exception as exc:  # noqa: BLE001 - anything else is a traceback to the user
            return "traceback", f"{type(exc).__name__}: {exc}"
    return _judge_return(case, value, caught)


_ERROR_LINE = re.compile(r"^meshladar( [\w-]+)*: error: ")


def _run_cli(case, tmp):
    from meshladar import cli as cli_module

    argv = [a.replace("{tmp}", str(tmp)) for a in case.call]
    out, err = io.StringIO(), io.StringIO()
    formatwarning = warnings.formatwarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = cli_module.main(argv)
                except SystemExit as exc:                 # argparse: --help, usage errors
                    code = 0 if exc.code is None else exc.code
        except Exception as exc:  # noqa: BLE001 - escaped main()
            return "traceback", f"{type(exc).__name__} escaped main(): {exc}"
        finally:
            warnings.formatwarning = formatwarning
    text = err.getvalue()
    lines = text.strip("\n").splitlines()
    if "Traceback" in text:
        return "traceback", text.strip()[-300:]
    if code == 0:
        return _judge_return(case, tmp, caught)
    if code == 1:
        return "traceback", _internal_error(text)
    if code != 2:
        return "traceback", f"exit status {code!r}: {_first_line(text)}"
    if not lines:
        return "vague", "exit status 2 and nothing on stderr"
    last = lines[-1]
    usage_only = all(line.startswith("usage:") or line.startswith(" ") for line in lines[:-1])
    if not _ERROR_LINE.match(last) or (len(lines) > 1 and not usage_only):
        return "vague", " | ".join(lines)[:300]
    return _judge_error(case, last)


def _internal_error(text):
    """The CLI's one-line internal error, with the exception from the traceback file it
    names (the file is removed)."""
    line = _first_line(text)
    m = re.search(r"traceback in (\S+\.txt)", text)
    if m and os.path.exists(m.group(1)):
        with open(m.group(1), encoding="utf-8") as fh:
            tail = fh.read().strip().splitlines()
        os.remove(m.group(1))
        if tail:
            line += f" [{tail[-1]}]"
    return line


class WorkStarted(Exception):
    """Raised by a function a case must not reach (its bad input is refused before)."""


@contextlib.contextmanager
def forbidding(targets):
    """Replace each "module:function" by one raising WorkStarted, for the duration."""
    import importlib

    saved = []
    try:
        for target in targets:
            module_name, name = target.split(":")
            try:
                module = importlib.import_module(module_name)
                saved.append((module, name, getattr(module, name)))
            except (ImportError, AttributeError):
                if _BEFORE:                             # an older meshladar: nothing to guard
                    continue
                raise                                   # a guard that guards nothing is a defect

            def reached(*args, _target=target, **kwargs):
                raise WorkStarted(f"{_target} was called: the work started before the bad "
                                  "input was refused")
            setattr(module, name, reached)
        yield
    finally:
        for module, name, original in reversed(saved):
            setattr(module, name, original)


def run_case(case, tmp):
    """Run one case in folder ``tmp`` (also the working folder): (outcome, message)."""
    tmp = Path(tmp)
    if case.precheck is not None and not case.precheck():
        return "traceback", "not refused up front: the cheap pre-check failed, not run"
    beside = f"{glob.escape(tmp.name)}.*"          # "-o FOLDER" must not write FOLDER.png
    before = set(tmp.parent.glob(beside))
    with contextlib.chdir(tmp):
        if case.setup is not None:
            case.setup(tmp)
        with forbidding(case.forbid), memory_guard():
            outcome, message = (_run_api if case.kind == "api" else _run_cli)(case, tmp)
    stray = sorted(set(tmp.parent.glob(beside)) - before)
    for path in stray:
        path.unlink()
    if stray:
        return "wrong", f"wrote {', '.join(p.name for p in stray)} beside its folder"
    late = re.search(r"(\S+:\S+) was called: the work started before the bad input", message)
    if late:
        return "late", f"the work started before the bad input was refused ({late.group(1)})"
    return outcome, message


# ================================================================== the test

import pytest  # noqa: E402


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case, tmp_path):
    if case.skip_root and hasattr(os, "geteuid") and os.geteuid() == 0:
        pytest.skip("root ignores file permissions")
    outcome, message = run_case(case, tmp_path)
    want = EXPECTED[case.expect]
    if outcome != want:
        pytest.fail(f"{case.id}: expected {case.expect} ({want}), got {outcome}: {message}",
                    pytrace=False)


# ================================================================== the report

#: Seconds a case may take in the report before it counts as a hang.
REPORT_TIMEOUT = 120
#: Address space of a report child.
REPORT_MEMORY = 6 * 2**30
_MARK = "@@matrix-result@@"
_MISSING_NAME = re.compile(r"(module 'meshladar[\w.]*' has no attribute|No module named "
                           r"'meshladar|cannot import name .* from 'meshladar|type object "
                           r"'\w+' has no attribute)")


def _child(case_id):
    """Run one case in this process (a report child) and print its result."""
    import resource
    import tempfile

    resource.setrlimit(resource.RLIMIT_AS, (REPORT_MEMORY, REPORT_MEMORY))
    case = next(c for c in CASES if c.id == case_id)
    with tempfile.TemporaryDirectory(prefix="matrix-") as tmp:
        if case.skip_root and os.geteuid() == 0:
            outcome, message = "skipped", "root ignores file permissions"
        else:
            try:
                outcome, message = run_case(case, tmp)
            except Exception as exc:  # noqa: BLE001 - the case's own setup failed
                outcome, message = "traceback", f"setup: {type(exc).__name__}: {exc}"
        if outcome == "traceback" and _MISSING_NAME.search(message):
            outcome = "n/a"
        for root, dirs, _ in os.walk(tmp):          # read-only folders, for the cleanup
            for d in dirs:
                os.chmod(os.path.join(root, d), 0o755)
    sys.stdout.write(f"\n{_MARK}{json.dumps({'outcome': outcome, 'message': message})}\n")
    sys.stdout.flush()


def _spawn(case, before):
    import signal
    import subprocess

    env = dict(os.environ)
    if before:
        env["MESHLADAR_MATRIX_BEFORE"] = os.path.abspath(before)
    proc = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", case.id],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=REPORT_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return "hang", f"no answer within {REPORT_TIMEOUT} s"
    for line in reversed(out.splitlines()):
        if line.startswith(_MARK):
            result = json.loads(line[len(_MARK):])
            return result["outcome"], result["message"]
    if proc.returncode < 0:
        return "traceback", f"killed by signal {-proc.returncode}"
    return "traceback", f"child exit {proc.returncode}: {_first_line(err[-500:])}"


def report(argv):
    import time
    from concurrent.futures import ThreadPoolExecutor

    before = argv[argv.index("--before") + 1] if "--before" in argv else _BEFORE
    only = argv[argv.index("--only") + 1] if "--only" in argv else ""
    cases = [c for c in CASES if only in c.id]
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max(1, min(2, os.cpu_count() or 1))) as pool:
        results = list(pool.map(lambda c: _spawn(c, before), cases))
    seconds = time.perf_counter() - t0
    counts = {}
    for outcome, _ in results:
        counts[outcome] = counts.get(outcome, 0) + 1
    print(f"meshladar {ml.__version__} from {os.path.dirname(ml.__file__)}: {len(cases)} cases "
          f"in {seconds:.0f} s")
    for outcome in ("clear", "vague", "traceback", "late", "warned", "accepted", "wrong",
                    "hang", "n/a", "skipped"):
        if outcome in counts:
            print(f"  {outcome:<10} {counts[outcome]:4d}")
    mismatches = [(c, o, m) for c, (o, m) in zip(cases, results)
                  if o not in (EXPECTED[c.expect], "skipped", "n/a")]
    nonsense = sum(1 for c, o, _ in mismatches if o == "accepted")
    print(f"\n{len(mismatches)} mismatches ({nonsense} silent nonsense):")
    for c, o, m in mismatches:
        print(f"  {c.id:<48} expected {c.expect:<5} got {o:<9} {_first_line(m)[:200]}")
    if "--json" in argv:
        with open(argv[argv.index("--json") + 1], "w", encoding="utf-8") as fh:
            json.dump([{"id": c.id, "expect": c.expect, "outcome": o, "message": m}
                       for c, (o, m) in zip(cases, results)], fh, indent=1)
    return 0


if __name__ == "__main__":
    if "--child" in sys.argv:
        _child(sys.argv[sys.argv.index("--child") + 1])
    elif "--report" in sys.argv:
        sys.exit(report(sys.argv))
    else:
        print(__doc__)
