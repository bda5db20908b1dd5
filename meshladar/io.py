"""Result files (formerly ``meshladar.results``): saving and loading results: atomic writes,
no pickle.

Results are ``.npz`` archives of plain arrays plus a JSON document (parameters, metrics,
version) stored as a string array under the key ``"__meta__"``. Files are written to a
temporary name in the destination folder and renamed over the target, so a crash never
leaves a half-written result, and loaded with ``allow_pickle=False``.
"""

from __future__ import annotations

import json
import math
import os
import stat
import warnings

import numpy as np

from . import _atomic_write, _validate
# the atomic writer (its own module), re-exported here, where it always was
from ._atomic_write import (_atomic, regular_file, temporary_writer, write_atomic,
                            write_text_atomic)
from ._atomic_write import _SWEPT  # noqa: F401  (the deprecated meshladar.results offers it)
from ._version import __version__
from ._validate import check_path
from .errors import MeshladarError, MeshladarWarning, ParameterError, user_stacklevel
from .noise import Noise
from .sinogram import Sinogram, check_sinogram
from .waveforms import Waveforms

__all__ = ["save_result", "load_result", "write_atomic", "write_text_atomic", "save_sinogram",
           "load_sinogram", "save_waveforms", "load_waveforms", "describe_scene",
           "ResultFileError", "TEMPORARY_PREFIX", "temporary_writer"]

# the writer's prefix, documented here, where it is public
#: The prefix of the temporaries meshladar writes beside a file before renaming it into
#: place: ``.meshladar-tmp-<pid>-<8 random characters><final name>``. Only names of exactly
#: that form are ever cleaned up, so a user's own ``.tmp-…`` files are never touched.
TEMPORARY_PREFIX = _atomic_write.TEMPORARY_PREFIX


class ResultFileError(MeshladarError, ValueError):
    """A result file is missing, unreadable, or not a meshladar result.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


def save_result(path, arrays: dict, meta: dict):
    """Save named float/int arrays and a JSON-serialisable ``meta`` dict atomically.

    The file is a compressed ``.npz`` (``numpy.savez_compressed``) written through
    :func:`write_atomic`; ``meta``, with ``meshladar_version`` added, is stored as JSON
    text (sorted keys) under the key ``"__meta__"``.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write; not a folder.
    arrays : dict
        Names (str, not ``"__meta__"``) to array_like values of a numeric dtype (no object
        arrays: files are loaded without pickle).
    meta : dict
        JSON-serialisable metadata.

    Raises
    ------
    ParameterError
        When ``path`` is not a non-empty path or names a folder, ``arrays`` or ``meta`` is
        not a dict, a name is not a str or is ``"__meta__"``, an array is of object dtype,
        or ``meta`` is not JSON-serialisable.
    OSError
        As :func:`write_atomic`.
    """
    path = check_path("path", path)
    if os.path.isdir(path):
        raise ParameterError(f"path must name a file, not a folder; got {path!r}")
    if not isinstance(arrays, dict) or not isinstance(meta, dict):
        raise ParameterError(f"arrays and meta must be dicts; got {type(arrays).__name__} and "
                             f"{type(meta).__name__}")
    payload = {}
    for k, v in arrays.items():
        a = np.asarray(v)
        if not isinstance(k, str) or k == "__meta__" or a.dtype.hasobject:
            raise ParameterError(f"arrays must map names (not '__meta__') to numeric arrays "
                                 f"(loaded without pickle); got {k!r}: {a.dtype}")
        payload[k] = a
    try:
        text = json.dumps(dict(meta, meshladar_version=__version__), sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"meta must be JSON-serialisable; {exc}") from None
    payload["__meta__"] = np.array(text)
    _atomic(path, lambda fh: np.savez_compressed(fh, **payload))


def load_result(path):
    """Load a result saved by :func:`save_result`: (arrays dict, meta dict).

    Loaded with ``allow_pickle=False``; before any array is read, the members' declared
    sizes are checked against their stored sizes and meshladar's allocation cap (4 GiB).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` file.

    Returns
    -------
    arrays : dict
        Name to numpy.ndarray, every member but ``"__meta__"``.
    meta : dict
        The parsed JSON metadata (with ``meshladar_version``).

    Raises
    ------
    ParameterError
        When ``path`` is not a non-empty str or os.PathLike.
    ResultFileError
        When the file is missing, unreadable, not a regular file, not an ``.npz`` (a file
        that does not begin as a zip archive is refused before numpy reads it, its kind
        named where its first bytes tell: an STL or PLY mesh, a LAS or HDF5 file, a bare
        ``.npy``), damaged (a member declaring more bytes than it holds, or failing to
        read), too large to unpack, without metadata, or with metadata that is not a JSON
        object.
    """
    path = check_path("path", path)
    try:
        kind = os.stat(path).st_mode
    except FileNotFoundError:
        raise ResultFileError(f"{path}: no such result file") from None
    except OSError as exc:
        raise ResultFileError(f"{path}: cannot be read ({exc.strerror})") from None
    if not stat.S_ISREG(kind):
        # a FIFO or a device would block or stream forever: refused before opening
        raise ResultFileError(f"{path}: not a regular file (a result file is an .npz)")
    try:
        with open(path, "rb") as fh:
            _check_zip(path, fh)
            with np.load(fh, allow_pickle=False) as z:
                _check_declared_sizes(path, z)
                arrays = {k: z[k] for k in z.files}
    except ResultFileError:
        raise
    except FileNotFoundError:
        raise ResultFileError(f"{path}: no such result file") from None
    except Exception as exc:  # noqa: BLE001 - a damaged or crafted file can fail anywhere in
        # numpy's reader (zlib.error, SyntaxError in a header, BadZipFile, ...): all mean
        # the same to the user
        raise ResultFileError(f"{path}: not a readable result file "
                              f"({type(exc).__name__}: {str(exc)[:160]})") from exc
    if "__meta__" not in arrays:
        raise ResultFileError(f"{path}: not a meshladar result (no metadata)")
    try:
        meta = json.loads(str(arrays.pop("__meta__")))
    except (ValueError, RecursionError) as exc:
        raise ResultFileError(f"{path}: damaged metadata (not JSON: {exc})") from exc
    if not isinstance(meta, dict):
        raise ResultFileError(f"{path}: damaged metadata (a JSON {type(meta).__name__}, not "
                              "an object)")
    return arrays, meta


#: A zip archive's first bytes (a local file header, or an empty archive's end record).
_ZIP_MAGIC = (b"PK\x03\x04", b"PK\x05\x06")
#: The first bytes of files a result is mistaken for, and what they are.
_NOT_NPZ = ((b"\x93NUMPY", "a bare .npy array"), (b"\x89HDF", "an HDF5 file"),
            (b"LASF", "a LAS point cloud"), (b"ply", "a PLY mesh"),
            (b"solid", "an ASCII STL mesh"), (b"glTF", "a GLB model"))


def _check_zip(path, fh):
    """Refuse a file that does not begin as a zip archive, before numpy's reader (which
    takes any other file for a pickle and says so), naming what it looks like; ``fh`` is
    left at its start."""
    head = fh.read(84)
    fh.seek(0)
    if head[:4] in _ZIP_MAGIC:
        return
    kinds = [kind for magic, kind in _NOT_NPZ if head.startswith(magic)]
    if len(head) == 84 and 84 + 50 * int.from_bytes(head[80:], "little") == \
            os.fstat(fh.fileno()).st_size:       # a binary STL's size is its triangles'
        kinds.insert(0, "a binary STL mesh")
    what = (f"it looks like {kinds[0]}" if kinds else "an empty file" if not head
            else "its first bytes are not a zip archive's")
    raise ResultFileError(f"{path}: not a readable result file: not an .npz archive "
                          f"({what}); give an .npz file that meshladar wrote")


def _check_declared_sizes(path, z):
    """Refuse, before reading any array, a result file whose members would unpack to more
    than meshladar's allocation cap, or whose array headers claim more bytes than their
    members hold (a crafted header would otherwise allocate what it claims)."""
    if not hasattr(z, "zip"):
        raise ResultFileError(f"{path}: not a meshladar result (a bare .npy, not an .npz)")
    total = 0
    for info in z.zip.infolist():
        total += info.file_size
        with z.zip.open(info) as member:
            version = np.lib.format.read_magic(member)
            read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                    else np.lib.format.read_array_header_2_0)
            shape, _, dtype = read(member)
        need = math.prod(shape) * dtype.itemsize
        if need > info.file_size:
            raise ResultFileError(f"{path}: damaged ({info.filename} declares {need} bytes "
                                  f"of data but holds {info.file_size})")
    if total > _validate.MAX_ARRAY_BYTES:
        raise ResultFileError(f"{path}: its arrays would unpack to {total / 2**30:.3g} GiB, "
                              f"more than the {_validate.MAX_ARRAY_BYTES / 2**30:g} GiB "
                              "meshladar reads at once")


def describe_scene(scene) -> dict:
    """A JSON-serialisable description of a scene: shapes or mesh parts, and coatings.

    Parameters
    ----------
    scene : Scene
        A mesh or analytic scene.

    Returns
    -------
    dict
        For a mesh scene: ``kind`` ``"mesh"``, ``materials`` (each coating's
        ``describe()``), ``parts`` (per part its ``name``, ``faces`` and ``vertices``
        counts and ``digest``) and ``report`` (the mesh checks). For an analytic scene:
        ``kind`` ``"analytic"`` and ``shapes`` (per shape its ``type``, ``name``,
        ``center``, ``semi_axes``, ``angle_deg`` (0 for a disk) and ``material``).
    """
    def mat(m):
        return m.describe()

    if scene.is_mesh:
        return {"kind": "mesh", "materials": [mat(m) for m in scene.materials],
                "parts": [{"name": p.name, "faces": int(len(p.faces)),
                           "vertices": int(len(p.vertices)), "digest": p.digest()}
                          for p in scene.parts], "report": {
                    k: v for k, v in scene.report.items()}}
    shapes = []
    for s in scene.shapes:
        shapes.append({"type": type(s).__name__, "name": s.name, "center": list(s.center),
                       "semi_axes": list(s.axes), "angle_deg": float(getattr(s, "angle_deg",
                                                                             0.0)),
                       "material": mat(s.material)})
    return {"kind": "analytic", "shapes": shapes}


def save_sinogram(path, sino, *, scene=None, params=None):
    """Save a sinogram with everything needed to reconstruct and plot it: values, angles,
    bin edges, view vectors, the model and its info, a description of the scene and its
    coatings, the run's parameters, and meshladar's version. Atomic, no pickle.

    The typed fields ``radiometry`` and ``units`` are written inside ``meta["info"]``, as
    before they were fields: files read both ways.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (an ``.npz``, :func:`save_result`).
    sino : Sinogram
        The sinogram: ``values``, ``angles_deg``, ``bin_edges`` and ``view_vectors`` are
        stored as arrays, ``model`` and ``info`` in the metadata.
    scene : Scene, optional
        Described in ``meta["scene"]`` (:func:`describe_scene`; default None).
        Keyword-only.
    params : dict, optional
        The run's parameters, stored in ``meta["params"]`` (numpy values as numbers and
        lists, anything else not JSON as its repr). Keyword-only.

    Raises
    ------
    ParameterError
        When ``sino`` is not a Sinogram, or :func:`save_result` refuses the path.
    OSError
        As :func:`write_atomic`.
    """
    check_sinogram("sino", sino)
    meta = {"kind": "sinogram", "model": sino.model, "info": _jsonable(sino.info),
            "scene": None if scene is None else describe_scene(scene),
            "params": _jsonable(params or {})}
    save_result(path, {"values": sino.values, "angles_deg": sino.angles_deg,
                       "bin_edges": sino.bin_edges, "view_vectors": sino.view_vectors}, meta)


def load_sinogram(path):
    """Load a sinogram saved by :func:`save_sinogram`: (Sinogram, meta). ``radiometry``
    and ``units`` in the stored info fill the record's typed fields.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` file.

    Returns
    -------
    sino : Sinogram
        The sinogram (``model`` default ``"measured"`` when the file has none).
    meta : dict
        The file's metadata (``kind``, ``model``, ``info``, ``scene``, ``params``,
        ``meshladar_version``).

    Raises
    ------
    ParameterError
        When ``path`` is not a non-empty str or os.PathLike.
    ResultFileError
        When :func:`load_result` fails, the file is not a sinogram result, lacks
        ``values``, ``angles_deg`` or ``bin_edges``, or its arrays do not make a valid
        Sinogram.
    """
    arrays, meta = load_result(path)
    if meta.get("kind") != "sinogram":
        raise ResultFileError(f"{os.fspath(path)}: not a sinogram result (kind "
                              f"{meta.get('kind')!r})")
    missing = [k for k in ("values", "angles_deg", "bin_edges") if k not in arrays]
    if missing:
        raise ResultFileError(f"{os.fspath(path)}: sinogram result lacks {missing[0]!r}")
    try:
        angles, vectors = arrays["angles_deg"], arrays.get("view_vectors")
        if not _validate.views_agree(angles, vectors):      # made-up angles of an old file
            warnings.warn(f"{os.fspath(path)}: its angles_deg contradict its view_vectors (a "
                          "file from before angles_deg became optional with 3-D views may "
                          "hold made-up angles): the views' azimuths are used",
                          MeshladarWarning, stacklevel=user_stacklevel())
            angles = None
        sino = Sinogram(arrays["values"], angles_deg=angles,
                        bin_edges=arrays["bin_edges"], model=meta.get("model", "measured"),
                        info=meta.get("info", {}), view_vectors=vectors)
    except ValueError as exc:
        raise ResultFileError(f"{os.fspath(path)}: invalid sinogram ({exc})") from exc
    return sino, meta


def save_waveforms(path, waves, *, realisations=None, noise=None, params=None):
    """Save waveforms (and, optionally, noise realisations (n, n_views, n_samples) and the
    :class:`~meshladar.noise.Noise` that drew them): values, time edges in s, range
    edges in m, views, every parameter with its unit in ``meta["info"]``; with both
    realisations and noise, ``meta["noise"]["clipped_fraction"]`` is the realisations'
    fraction at the digitiser's top code (:meth:`~meshladar.noise.Noise.clipped_fraction`).
    Atomic, no pickle.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (an ``.npz``, :func:`save_result`).
    waves : Waveforms
        Stored as arrays ``values``, ``time_edges_s``, ``range_edges_m``, ``angles_deg``
        and ``view_vectors``; its standoff as ``meta["standoff_m"]``.
    realisations : (n, n_views, n_samples) array_like, optional
        Noise realisations, stored as float64 ``realisations`` (shape not checked).
        Keyword-only.
    noise : Noise, optional
        Described in ``meta["noise"]`` (anything else is stored as None). Keyword-only.
    params : dict, optional
        The run's parameters, stored in ``meta["params"]``. Keyword-only.

    Raises
    ------
    ParameterError
        When ``waves`` is not a Waveforms, or :func:`save_result` refuses the path or
        arrays.
    OSError
        As :func:`write_atomic`.
    """
    if not isinstance(waves, Waveforms):
        raise ParameterError(f"waves must be a meshladar.waveforms.Waveforms; got "
                             f"{type(waves).__name__}")
    arrays = {"values": waves.values, "time_edges_s": waves.time_edges,
              "range_edges_m": waves.range_edges, "angles_deg": waves.angles_deg,
              "view_vectors": waves.view_vectors}
    if realisations is not None:
        arrays["realisations"] = np.asarray(realisations, dtype=np.float64)
    described = None if not isinstance(noise, Noise) else noise.describe()
    if described is not None and realisations is not None:
        described["clipped_fraction"] = noise.clipped_fraction(arrays["realisations"])
    meta = {"kind": "waveforms", "standoff_m": waves.standoff, "info": _jsonable(waves.info),
            "noise": described, "params": _jsonable(params or {})}
    save_result(path, arrays, meta)


def load_waveforms(path):
    """Load waveforms saved by :func:`save_waveforms`: (Waveforms, realisations or None,
    meta).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` file.

    Returns
    -------
    waves : Waveforms
        The waveforms (standoff from ``meta["standoff_m"]``, default 0.0).
    realisations : numpy.ndarray or None
        The stored noise realisations, or None when the file has none.
    meta : dict
        The file's metadata (``kind``, ``standoff_m``, ``info``, ``noise``, ``params``,
        ``meshladar_version``).

    Raises
    ------
    ParameterError
        When ``path`` is not a non-empty str or os.PathLike.
    ResultFileError
        When :func:`load_result` fails, the file is not a waveforms result, or it lacks an
        array or its arrays do not make valid Waveforms.
    """
    arrays, meta = load_result(path)
    if meta.get("kind") != "waveforms":
        raise ResultFileError(f"{os.fspath(path)}: not a waveforms result (kind "
                              f"{meta.get('kind')!r})")
    try:
        waves = Waveforms(arrays["values"], time_edges=arrays["time_edges_s"],
                          angles_deg=arrays["angles_deg"], view_vectors=arrays["view_vectors"],
                          standoff=meta.get("standoff_m", 0.0), info=meta.get("info", {}))
    except (KeyError, ValueError) as exc:
        raise ResultFileError(f"{os.fspath(path)}: invalid waveforms ({exc})") from exc
    return waves, arrays.get("realisations"), meta


def _jsonable(x):
    """Plain JSON types for metadata (numpy scalars and arrays become numbers and lists;
    anything else its repr)."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    if x is None or isinstance(x, (bool, int, float, str)):
        return x
    return repr(x)
