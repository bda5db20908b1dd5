"""Points files' formats by extension, and the checks made before a scan writes one: one
table (:data:`FORMATS`) for the writers, the waveform sink and the command line."""

from __future__ import annotations

import importlib.util
import os

from .._validate import check_path
from ..errors import ParameterError

__all__ = ["FORMATS", "points_format", "check_writable"]

#: Each points file's extension, the format it names and the writer of that format.
FORMATS = {".las": ("LAS", "write_las"), ".laz": ("LAS", "write_las"),
           ".h5": ("HDF5", "write_hdf5"), ".hdf5": ("HDF5", "write_hdf5"),
           ".npz": ("NPZ", "write_npz")}
#: The packages each format's writer needs (any one of a tuple): numpy's .npz none.
_NEEDS = {".las": ("laspy",), ".laz": ("laspy", ("lazrs", "laszip")), ".h5": ("h5py",),
          ".hdf5": ("h5py",), ".npz": ()}

def check_writable(path, flag="path", folder=True):
    """Refuse, before any work, a points file that cannot be written: a folder, a file in
    a folder that does not exist (unless ``folder`` is False), or one whose writer is not
    installed (laspy for ``.las``, laspy and lazrs (or laszip) for ``.laz``, h5py for
    ``.h5``/``.hdf5``; ``.npz`` needs numpy alone).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.
    flag : str
        The option or argument named in the message.
    folder : bool
        Whether the file's folder must exist (the command line makes a missing one, its
        nearest existing folder checked by its own output checks).

    Returns
    -------
    str
        The path, as a string.

    Raises
    ------
    ParameterError
        Naming the folder, or the missing package and the extra that installs it.
    """
    path = _target(path, flag, folder)
    need = _NEEDS.get(os.path.splitext(path)[1].lower(), _NEEDS[".las"])
    for module in need:
        options = module if isinstance(module, tuple) else (module,)
        if not any(importlib.util.find_spec(m) is not None for m in options):
            raise ParameterError(f"{flag}: writing {path!r} needs {options[0]}, "
                                 "which is not installed: pip install 'meshladar[scan]'")
    return path


def _target(path, flag, exists=True):
    """``path`` checked to name a file (not a folder) in a folder that exists (with
    ``exists``)."""
    path = check_path(flag, path)
    if os.path.isdir(path):
        raise ParameterError(f"{flag}: {path!r} is a folder; name a file in it")
    folder = os.path.dirname(os.path.abspath(path))
    if exists and not os.path.isdir(folder):
        raise ParameterError(f"{flag}: no folder {folder!r} to write {path!r} into")
    return path


def points_format(path):
    """The format a points file's extension names (:data:`FORMATS`): ``"LAS"`` (.las,
    .laz), ``"HDF5"`` (.h5, .hdf5), ``"NPZ"`` (.npz), or None for any other extension.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str or None
    """
    return FORMATS.get(os.path.splitext(os.fspath(path))[1].lower(), (None,))[0]


def _not_named_as(path, writes, flag="path"):
    """``path``, refused where its extension names a format other than ``writes``."""
    named = points_format(path)
    if named not in (None, writes):
        writer = FORMATS[os.path.splitext(path)[1].lower()][1]
        raise ParameterError(f"{flag}: {path!r} names a{'n' if named != 'LAS' else ''} "
                             f"{named} file; {writer} writes that format")
    return path
