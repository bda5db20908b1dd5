"""Recognising a mesh file before trimesh reads it: format by suffix or content (magic
numbers, headers), single-file compression undone with the standard library, archive
listings, optional readers, and the one-line messages that name what is wrong.
"""

from __future__ import annotations

import bz2
import contextlib
import gzip
import importlib.util
import io
import logging
import lzma
import os
import re
import tarfile
import warnings
import zipfile

from .. import _validate
from ..errors import GeometryError

__all__: list[str] = []


#: Bytes read from the start of a file to recognise its format by content (magic numbers,
#: headers, the first lines of a text format).
_HEAD_BYTES = 1 << 16
#: Longest piece of a reader's own message quoted in a GeometryError (characters).
_MAX_REASON = 160
#: Single-file compression meshladar undoes itself with the standard library, then reads the
#: inner file by its own suffix (or content): trimesh reads neither .gz nor .xz, and its
#: .bz2 reader hides why the inner file failed.
_COMPRESSED = {"gz": "gzip", "bz2": "bzip2", "xz": "xz"}
#: Tar archives, by suffix, as trimesh's archive reader names them. Its reader opens any tar
#: with ``tarfile.open(mode="r")``, which detects the compression itself, so plain and xz tars
#: go through 'tar.gz' too.
_TAR = {"tar.gz": "tar.gz", "tgz": "tar.gz", "tar.bz2": "tar.bz2", "tbz2": "tar.bz2",
        "tbz": "tar.bz2", "tar.xz": "tar.gz", "txz": "tar.gz", "tar": "tar.gz"}
#: Formats trimesh reads only with an optional package installed (pip names), as its
#: ``trimesh.exchange`` modules import them: COLLADA through pycollada, 3MF and 3DXML through
#: lxml and networkx, XAML through lxml, STEP through cascadio, OpenCTM through openctm, and
#: the volume and finite-element formats through meshio. (SVG, through svg.path and lxml, is
#: a 2-D drawing format: see _DRAWINGS.)
_OPTIONAL_READERS = {
    "dae": "pycollada", "zae": "pycollada", "3mf": "lxml networkx", "3dxml": "lxml networkx",
    "xaml": "lxml", "step": "cascadio", "stp": "cascadio", "ctm": "openctm",
    **dict.fromkeys(("vtk", "vtu", "msh", "inp", "mesh", "meshb", "med", "xdmf", "xmf",
                     "h5m", "su2", "ugrid", "mdpa", "bdf", "fem", "nas", "avs", "cgns",
                     "exo", "e", "tec", "f3grid", "vol"), "meshio"),
}
#: Formats that hold 2-D drawings (trimesh Path2D), never a 3-D triangle mesh.
_DRAWINGS = {"svg": "svg.path lxml", "dxf": ""}
#: What each format is called in messages.
_NAMES = {"stl": "STL file", "obj": "OBJ file", "ply": "PLY file", "off": "OFF file",
          "glb": "GLB file", "gltf": "glTF file", "zip": "ZIP archive", "tar.gz": "tar archive",
          "tar.bz2": "tar archive", "bz2": "bzip2 file", "gz": "gzip file", "xz": "xz file",
          "dxf": "DXF drawing", "svg": "SVG drawing", "xyz": "XYZ point file",
          "dae": "COLLADA file", "3mf": "3MF file"}

#: The module a pip package is imported as, where the two differ.
_IMPORT_NAMES = {"pycollada": "collada", "Pillow": "PIL"}
#: The pip package of a top-level module, where the two differ (a reader's ImportError names
#: the module).
_PIP_NAMES = {**{module: pip for pip, module in _IMPORT_NAMES.items()}, "svg": "svg.path"}


def _count(n, one, many=None):
    """'1 point', '2 points'."""
    return f"{n} {one if n == 1 else (many or one + 's')}"


def _readable_formats():
    """The formats this trimesh reads with what is installed ('stl_ascii' is an alias)."""
    import trimesh

    return set(trimesh.available_formats()) - {"stl_ascii"}


def _installed(module):
    """Whether a module can be found (without importing it)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):              # a dotted name whose parent is missing
        return False


def _missing(ftype, exc=None):
    """The pip packages a format's reader needs that are not installed: those of the table
    that cannot be found, and the module the reader's ImportError names (trimesh's 3DXML
    reader needs Pillow for a textured file, which no table entry says), if it is missing."""
    pkgs = (_OPTIONAL_READERS.get(ftype) or _DRAWINGS.get(ftype) or "").split()
    missing = [p for p in pkgs if not _installed(_IMPORT_NAMES.get(p, p))]
    module = (getattr(exc, "name", None) or "").split(".")[0]
    if module and not _installed(module):
        pip = _PIP_NAMES.get(module, module)
        missing += [] if pip in missing else [pip]
    return missing


def _needs(where, ftype, exc=None):
    """The message for a format whose optional reader is not installed (``exc``: the
    ImportError its reader raised), naming only the packages that are missing."""
    missing = _missing(ftype, exc)
    if not missing and exc is None:                # the format is not registered: its table
        missing = (_OPTIONAL_READERS.get(ftype) or _DRAWINGS.get(ftype) or "").split()
    if missing:
        return (f"{where}: reading {_label(ftype)} files needs the optional package"
                f"{'s' if len(missing) > 1 else ''} {' and '.join(missing)}: "
                f"pip install {' '.join(missing)}")
    return (f"{where}: reading {_label(ftype)} files needs a package that is not installed "
            f"({_one_line(exc)})")


def _label(suffix):
    return f"'.{suffix}'"


def _name(ftype):
    return _NAMES.get(ftype, f"{ftype.upper()} file")


def _suffix(name):
    """Lower-case suffix of a file name without the dot ('tar.gz' style for tars), or ''."""
    base = os.path.basename(name).lower()
    for double in ("tar.gz", "tar.bz2", "tar.xz"):
        if base.endswith("." + double):
            return double
    stem, dot, ext = base.rpartition(".")
    return ext if dot and stem else ""


def _sniff(head, size):
    """The format a file's first bytes announce (magic numbers and headers), or None."""
    if head.startswith(b"glTF"):
        return "glb"
    if head.startswith(b"PK\x03\x04"):
        return "zip"
    if head.startswith(b"\x1f\x8b"):
        return "gz"
    if head.startswith(b"BZh"):
        return "bz2"
    if head.startswith(b"\xfd7zXZ\x00"):
        return "xz"
    if head[257:262] == b"ustar":
        return "tar"
    if head[:3] == b"ply" and head[3:4] in (b"\n", b"\r"):
        return "ply"
    # binary STL: an 80-byte header, a triangle count, 50 bytes per triangle
    if size >= 134 and 84 + 50 * int.from_bytes(head[80:84], "little") == size:
        return "stl"
    text = head[:4096].decode("utf-8", "replace").lstrip("\ufeff \t\r\n")
    low = text.lower()
    if low.startswith("solid") and "facet" in low:
        return "stl"
    if low.split(None, 1)[:1] in (["off"], ["coff"]):
        return "off"
    if low.startswith("{") and '"asset"' in low:
        return "gltf"
    if "<collada" in low:
        return "dae"
    if "<svg" in low:
        return "svg"
    if re.search(r"^\s*0\s*\n\s*section\s*$", low, re.M):
        return "dxf"
    if re.search(r"^v\s+\S+\s+\S+\s+\S+", text, re.M):
        return "obj"
    return None


def _is_binary(head):
    """True when the bytes are not text (a NUL byte, or not UTF-8 before the last char)."""
    if b"\x00" in head:
        return True
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        return exc.start < len(head) - 3
    return False


#: A compressed mesh file may unpack to at most this many times its own size (above the
#: floor below), and never past meshladar's allocation cap: real meshes compress 3-20:1, a
#: decompression bomb ~1000:1 (gzip) or far more (bzip2). Measured on the decompressed
#: bytes as they stream, so a bomb is refused in bounded memory and time.
EXPANSION_RATIO = 256
#: Decompressed bytes always allowed, whatever the ratio (64 MiB).
EXPANSION_FLOOR = 64 << 20
#: Bytes decompressed per read.
_BLOCK = 1 << 20


def expansion_limit(compressed_bytes):
    """The most bytes a compressed file of ``compressed_bytes`` may unpack to."""
    return min(_validate.MAX_ARRAY_BYTES,
               max(EXPANSION_FLOOR, EXPANSION_RATIO * int(compressed_bytes)))


def _too_large(where, limit, compressed):
    return GeometryError(
        f"{where}: unpacks to more than {limit / 2**20:.0f} MiB from {compressed} compressed "
        f"bytes (a decompression bomb, or a mesh beyond {EXPANSION_RATIO}:1 and "
        f"{_validate.MAX_ARRAY_BYTES / 2**30:g} GiB); decompress it yourself if you trust it")


def _decompress(path, kind, where, keep=True):
    """The decompressed bytes of a .gz/.bz2/.xz file (or, without ``keep``, their count),
    streamed and refused past :func:`expansion_limit`."""
    opener = {"gz": gzip.open, "bz2": bz2.open, "xz": lzma.open}[kind]
    size = os.path.getsize(path)
    limit = expansion_limit(size)
    blocks, total = [], 0
    try:
        with opener(path, "rb") as fh:
            while block := fh.read(_BLOCK):
                total += len(block)
                if total > limit:
                    raise _too_large(where, limit, size)
                if keep:
                    blocks.append(block)
    except GeometryError:
        raise
    except Exception as exc:                  # BadGzipFile, OSError, EOFError, LZMAError
        raise GeometryError(f"{where}: not a valid {_name(kind)} "
                            f"({type(exc).__name__}: {_one_line(exc)})") from exc
    return b"".join(blocks) if keep else total


def check_archive(path, head, where):
    """Refuse, before trimesh unpacks it, a ZIP whose members declare more than
    :func:`expansion_limit` of the file's size, or a compressed tar that streams past it."""
    size = os.path.getsize(path)
    limit = expansion_limit(size)
    if head.startswith(b"PK\x03\x04"):
        try:
            with zipfile.ZipFile(path) as z:
                total = sum(info.file_size for info in z.infolist())
        except Exception:                      # unreadable: trimesh's reader says why
            return
        if total > limit:
            raise _too_large(where, limit, size)
        return
    kind = _sniff(head, size)
    if kind in _COMPRESSED:                    # a compressed tar: stream it, keep nothing
        _decompress(path, kind, where, keep=False)


def _members(source, ftype):
    """' (files: a, b, ...)' of an archive, for a message; '' if it cannot be listed."""
    try:
        src = source()
        if ftype == "zip":
            with zipfile.ZipFile(src) as z:
                names = z.namelist()
        else:
            with (tarfile.open(src) if isinstance(src, str)
                  else tarfile.open(fileobj=src)) as t:
                names = t.getnames()
    except Exception:                          # only a nicety of the message
        return ""
    shown = ", ".join(names[:4]) + (f", ... ({len(names)} files)" if len(names) > 4 else "")
    return f" (files: {_one_line(shown)})" if names else " (it is empty)"


@contextlib.contextmanager
def _quiet_reader():
    """Keep a reader's own diagnostics off the terminal while trimesh reads a file:
    meshladar accepts the file or rejects it with its own one-line message. trimesh logs
    without a handler, so Python's last-resort handler would print its warnings (some with
    tracebacks); its ``warnings.warn`` calls (deprecations) are silenced in this scope only;
    what a reader prints (meshio's "Error: Couldn't read file ... as ansys" while it tries
    formats) goes to the StringIO this yields, for the message if the file then fails.
    Output written by compiled code straight to the file descriptors is not caught."""
    logger = logging.getLogger("trimesh")
    handler = logging.NullHandler()
    logger.addHandler(handler)
    said = io.StringIO()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(said), \
                contextlib.redirect_stderr(said):
            warnings.simplefilter("ignore")
            yield said
    finally:
        logger.removeHandler(handler)


def _with_output(err, said):
    """``err`` (a GeometryError) with what the reader printed, on one line, appended."""
    printed = said.getvalue().strip()
    if printed:
        err.args = (f"{err.args[0]} (the reader printed: {_one_line(printed)})",)
    return err


def _one_line(text):
    """``text`` on one line (whitespace runs collapsed, control characters escaped), cut to
    _MAX_REASON characters."""
    s = _printable(" ".join(str(text).split()))
    return s if len(s) <= _MAX_REASON else s[: _MAX_REASON - 3] + "..."


def _printable(path):
    """A path for a one-line message: line breaks and other control characters escaped."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in path)
