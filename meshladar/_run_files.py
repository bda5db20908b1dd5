"""Whose is a file with a run folder's name: meshladar's manifest, chunk or lock, told apart
from a file of the same name someone else made (:mod:`meshladar.runs` refuses a folder
holding one, since a run would overwrite it).

Pure functions: they read what they are given and return a verdict, ``(kind, detail)``:

- ``"ours"`` (a manifest) or ``"chunk"`` (a chunk file): meshladar's own file; the detail is
  the manifest's document, or the job digest the chunk records;
- ``"damaged"``: unreadable (not JSON, not a zip, a member failing its CRC), so whose it is
  cannot be told from the file: meshladar's own only where the folder proves it (the
  manifest, or a chunk, of this job beside it); the detail says what is wrong;
- ``"foreign"``: readable, and not meshladar's (a JSON object with other keys, an ``.npz``
  without a chunk's metadata): someone else's, never overwritten; the detail says what it is.
"""

from __future__ import annotations

import io
import json
import os
import re
import zipfile

import numpy as np

#: The keys of a run manifest; a JSON object with any other key is another program's file.
MANIFEST_KEYS = frozenset({"digest", "job", "meshladar_version"})
#: The keys a chunk file's metadata records (besides meshladar's version).
CHUNK_KEYS = ("job", "chunk", "sha256")
#: A run manifest is a few kilobytes; a file this large is not one.
MANIFEST_MAX_BYTES = 1 << 26
#: A chunk's metadata member is a few hundred bytes; one this large is not a chunk's.
META_MAX_BYTES = 1 << 20
#: What the lock file holds: nothing (just created) or the running process's id.
_LOCK_TEXT = re.compile(r"(pid \d+)?")


def owned(name):
    """Whether ``name`` is a run folder's own file name: the lock, the manifest, a chunk."""
    return name in (".lock", "manifest.json") or (name.startswith("chunk_")
                                                   and name.endswith(".npz"))


def manifest_kind(raw: bytes):
    """The verdict on a manifest file's bytes (read up to one past the largest a manifest
    has): ``("ours", document)``, ``("damaged", why)`` or ``("foreign", why)``."""
    if len(raw) > MANIFEST_MAX_BYTES:
        return "foreign", f"{len(raw)}+ bytes, more than any run manifest"
    try:
        doc = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError) as exc:      # UnicodeDecodeError is a ValueError
        return "damaged", "not JSON: " + " ".join(str(exc).split())[:120]
    if isinstance(doc, dict) and set(doc) - MANIFEST_KEYS:
        other = ", ".join(repr(k) for k in sorted(set(doc) - MANIFEST_KEYS)[:3])
        return "foreign", f"a JSON object with keys a run manifest never has ({other})"
    if (isinstance(doc, dict) and isinstance(doc.get("digest"), str)
            and isinstance(doc.get("job", {}), dict)):
        return "ours", doc
    return "damaged", f"a JSON {type(doc).__name__} without a job digest"


def chunk_kind(fh):
    """The verdict on a chunk file (``fh``: open for reading in binary): ``("chunk", job
    digest)``, ``("damaged", why)`` or ``("foreign", why)``. Only the metadata member is
    read (and, in a zip without one, every member's CRC): the arrays are verified on use."""
    try:
        with zipfile.ZipFile(fh) as zf:
            if "__meta__.npy" not in zf.namelist():
                bad = zf.testzip()                    # None: every member reads, CRC intact
                if bad is None:
                    return "foreign", "an .npz or zip without meshladar's chunk metadata"
                return "damaged", f"member {bad!r} fails its check"
            if zf.getinfo("__meta__.npy").file_size > META_MAX_BYTES:
                return "foreign", "metadata far larger than a chunk's"
            data = zf.read("__meta__.npy")            # its CRC checked: as its writer wrote it
    except Exception as exc:  # noqa: BLE001 - a damaged file can fail anywhere in zipfile
        # (BadZipFile, zlib.error, EOFError, OSError, ...): all mean it cannot be read
        return "damaged", f"not a readable .npz ({type(exc).__name__})"
    try:
        meta = json.loads(str(np.lib.format.read_array(io.BytesIO(data), allow_pickle=False)))
    except Exception:  # noqa: BLE001 - intact bytes that are not a JSON string: not ours
        meta = None
    if not (isinstance(meta, dict) and all(k in meta for k in CHUNK_KEYS)
            and isinstance(meta["job"], str)):
        return "foreign", "an .npz whose metadata is not a meshladar chunk's"
    return "chunk", meta["job"]


def lock_is_ours(fh):
    """Whether the lock file (``fh``: open in text mode, at its start) holds what meshladar
    writes there: nothing, or ``pid <n>``."""
    try:
        text = fh.read(256)
    except ValueError:                                  # not UTF-8 text
        return False
    return _LOCK_TEXT.fullmatch(text.strip()) is not None


def refusal(folder, name, what):
    """The one-line message refusing a run folder that holds someone else's ``name``."""
    return (f"{os.path.join(folder, name)}: {what}; a run here would overwrite it, and "
            f"meshladar never overwrites a file it did not write: choose an empty or new "
            f"folder for the run, or move {name} out of {folder}")


def non_finite(arrays):
    """The name of the first floating or complex array holding NaN or inf, else None."""
    for k in sorted(arrays):
        a = arrays[k]
        if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
            return k
    return None


def jsonable(x):
    """``x`` as JSON gives it back (anything JSON cannot encode as its ``str``)."""
    return json.loads(json.dumps(x, sort_keys=True, default=str))
