"""Saving and loading results: atomic writes, no pickle.

Results are ``.npz`` archives of plain arrays plus a JSON document (parameters, metrics,
version) stored as a string array under the key ``"__meta__"``. Files are written to a
temporary name in the destination folder and renamed over the target, so a crash never
leaves a half-written result, and loaded with ``allow_pickle=False``.
"""

from __future__ import annotations

import json
import os
import tempfile

import numpy as np

from .errors import MeshladarError

__all__ = ["save_result", "load_result", "write_text_atomic", "ResultFileError"]


class ResultFileError(MeshladarError, ValueError):
    """A result file is missing, unreadable, or not a meshladar result."""


def _atomic(path, write):
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=os.path.basename(path))
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_text_atomic(path, text: str):
    """Write a text file atomically (UTF-8)."""
    _atomic(path, lambda fh: fh.write(text.encode("utf-8")))


def save_result(path, arrays: dict, meta: dict):
    """Save named float/int arrays and a JSON-serialisable ``meta`` dict atomically."""
    from . import __version__

    payload = {k: np.asarray(v) for k, v in arrays.items()}
    if "__meta__" in payload:
        raise ValueError("'__meta__' is reserved")
    doc = dict(meta, meshladar_version=__version__)
    payload["__meta__"] = np.array(json.dumps(doc, sort_keys=True))
    _atomic(path, lambda fh: np.savez_compressed(fh, **payload))


def load_result(path):
    """Load a result saved by :func:`save_result`: (arrays dict, meta dict)."""
    path = os.fspath(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise ResultFileError(f"{path}: no such result file") from None
    except (OSError, ValueError) as exc:
        raise ResultFileError(f"{path}: not a readable result file ({exc})") from exc
    if "__meta__" not in arrays:
        raise ResultFileError(f"{path}: not a meshladar result (no metadata)")
    meta = json.loads(str(arrays.pop("__meta__")))
    return arrays, meta
