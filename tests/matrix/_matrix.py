"""The bad-input matrix's cases as data (issue 12): the :class:`Case` record, the two ways
to register one (:func:`api`, :func:`cli`) into :data:`CASES`, and the inputs the cases
share (built lazily, on first use, so that an older meshladar without a name fails that
case only).

The cases themselves are in ``_cases_values.py`` (files, BRDFs, shapes, the ladar),
``_cases_engine.py`` (simulate, trace and weigh, sinograms, reconstruction, result files,
coating tables, phantom specs, studies, the viewer) and ``_cases_cli.py`` (the command
line); ``test_matrix.py`` runs them. With ``MESHLADAR_MATRIX_BEFORE`` set (the report's
``--before``), this module puts that checkout first on sys.path before importing meshladar.
"""

from __future__ import annotations

import math
import os
import re
import sys
from dataclasses import dataclass
from functools import cache, partial

_BEFORE = os.environ.get("MESHLADAR_MATRIX_BEFORE")
if _BEFORE:
    sys.path.insert(0, os.path.abspath(_BEFORE))

import numpy as np  # noqa: E402

import meshladar as ml  # noqa: E402

nan, inf = math.nan, math.inf


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


def _box(**kw):
    """A unit box from trimesh as a scene (``material`` etc. as the case gives)."""
    return ml.Scene.from_mesh(_trimesh().creation.box(), **kw)


def _refuses_many_jobs():
    """True when a huge ``jobs`` is refused before any process starts."""
    from meshladar.errors import ParameterError
    from meshladar.stream import choose_executor as _executor

    try:
        ex, own = _executor(10**5, None, 1.0, 1)
    except ParameterError:
        return True
    if own:
        ex.shutdown()
    return False


#: Bin edges of the ladar cases (eight bins over [-1, 1]).
_EDGES = np.linspace(-1, 1, 9)


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
    # subdivisions 2: faces 0.18 rad apart, finer than dark gray's lobe (0.34 rad across), so
    # the flat-normal faceting warning has nothing to say on these cases
    return _trimesh().creation.icosphere(subdivisions=2, radius=0.5).export(file_type="stl")


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
