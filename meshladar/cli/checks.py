"""Output paths the command line writes, checked before any work: never an input, never
another output of the same command, never inside a run folder, always a known format, and
in a place that can hold them (the nearest existing folder above is a folder, writable)."""

from __future__ import annotations

import os
import tempfile

from .._atomic_write import TEMPORARY_PREFIX
from ..errors import ParameterError

__all__ = ["check_output", "check_outdir", "check_not_input", "check_place", "same_file"]


def check_place(path, flag, folder=False):
    """The place ``path`` would be written: the folders missing above it are created by
    the writer, so the nearest one that exists must be a folder this process may write in.

    Parameters
    ----------
    path : str
        The file (or, with ``folder``, the folder) to be written.
    flag : str
        The option or argument named in the message (``"-o"``, ``"outdir"``).
    folder : bool
        True when ``path`` is itself a folder to create or fill (``OUTDIR``,
        ``--run-dir``): an existing ``path`` is then the place itself.

    Raises
    ------
    ParameterError
        When the nearest existing path at or above the place is a file (``cone.stl/x.npz``
        with ``cone.stl`` a file), or a folder without write permission or that takes no
        new file (a read-only mount, ``/sys``: tried with a temporary, removed at once);
        naming ``flag``, ``path`` and that path.
    """
    above = os.path.abspath(path)
    if not folder or not os.path.exists(above):
        above = os.path.dirname(above)
        while not os.path.exists(above):
            if os.path.islink(above):               # a link to nothing: no folder to make
                raise ParameterError(f"{flag}: cannot write {path!r}: {above!r} is a link to "
                                     f"{os.readlink(above)!r}, which does not exist")
            above = os.path.dirname(above)
    if not os.path.isdir(above):
        raise ParameterError(f"{flag}: cannot write {path!r}: {above!r} is a file, not a "
                             "folder")
    if not os.access(above, os.W_OK | os.X_OK):
        raise ParameterError(f"{flag}: cannot write {path!r}: no permission to write in "
                             f"the folder {above!r}")
    try:        # what the permission bits do not tell (root on /sys, read-only mounts)
        fd, probe = tempfile.mkstemp(dir=above, prefix=f"{TEMPORARY_PREFIX}{os.getpid()}-",
                                     suffix="probe")     # named as a temporary: one a kill
    except OSError as exc:                               # leaves is cleaned up later
        raise ParameterError(f"{flag}: cannot write {path!r}: the folder {above!r} takes no "
                             f"new file ({exc.strerror})") from None
    try:
        os.close(fd)
    finally:
        os.remove(probe)


def check_outdir(outdir, flag="outdir"):
    """An output folder: a folder (existing or not), not a file, not empty, in a place
    that can hold it (:func:`check_place`).

    Parameters
    ----------
    outdir : str or None
        The folder's path. It need not exist (the command creates it); nothing is created
        here.
    flag : str
        The argument named in the messages (default ``"outdir"``; ``"--run-dir"``).

    Raises
    ------
    ParameterError
        When ``outdir`` is empty or None, names an existing path that is not a folder
        (a file), or lies under a file or in a folder without write permission.
    """
    if not outdir or (os.path.exists(outdir) and not os.path.isdir(outdir)):
        raise ParameterError(f"{flag} must name a folder; got {outdir!r}"
                             + (" (a file)" if outdir and os.path.exists(outdir) else ""))
    check_place(outdir, flag, folder=True)


def same_file(a, b):
    """Whether paths ``a`` and ``b`` name one file: the same path with links resolved (so
    also before either exists), or, when both exist, the same file.

    Parameters
    ----------
    a, b : str
        The paths.

    Returns
    -------
    bool
        True when writing one would overwrite the other.
    """
    return os.path.realpath(a) == os.path.realpath(b) or (
        os.path.exists(a) and os.path.exists(b) and os.path.samefile(a, b))


def _inside(path, folder):
    """Whether ``path`` is ``folder`` or lies under it (links resolved)."""
    real, top = os.path.realpath(path), os.path.realpath(folder)
    return real == top or os.path.commonpath([real, top]) == top


def check_output(output, suffixes, inputs, flag="-o", *, others=(), run_dir=None):
    """An output path must never name an input, another output or a run folder's file,
    and must name a file of a known format in a place that can hold it.

    Parameters
    ----------
    output : str or None
        The output file's path.
    suffixes : sequence of str
        The extensions accepted, lower case with their dot (e.g. ``(".npz",)``); the
        output's extension is compared in lower case.
    inputs : iterable of str or None
        The command's input paths; None entries (inputs not given) are skipped. The
        output may not be any of them (:func:`same_file`: the same path, links resolved,
        or when both exist the same file).
    flag : str
        The output's flag, named in the messages (default ``"-o"``).
    others : iterable of (str, str or None)
        The command's other outputs as ``(flag, path)`` pairs (None paths skipped): the
        output may not be one of them.
    run_dir : str, optional
        The run folder (``--run-dir``): it holds the run's own files (``manifest.json``,
        ``chunk_*.npz``, its lock), so the output may not lie in it, at any depth.

    Raises
    ------
    ParameterError
        When ``output`` is empty or None, names a folder (an existing one, or a path
        whose last component is empty, ``.`` or ``..``), is one of ``inputs`` or
        ``others``, lies in ``run_dir``, has an extension not in ``suffixes``, or cannot
        be written where it is (:func:`check_place`).
    """
    if not output or os.path.basename(output) in ("", ".", "..") or os.path.isdir(output):
        raise ParameterError(f"{flag}: must name a file, not a folder; got {output!r}")
    for src in filter(None, inputs):
        if same_file(src, output):
            raise ParameterError(f"{flag} {output!r} is the input {src!r}: meshladar never "
                                 "overwrites an input; choose another output name")
    for other, path in others:
        if path and same_file(path, output):
            raise ParameterError(f"{flag} {output!r} and {other} {path!r} are the same "
                                 "file: give each output its own")
    if run_dir and _inside(output, run_dir):
        raise ParameterError(f"{flag} {output!r} is in the run folder --run-dir "
                             f"{run_dir!r}, which holds the run's own files (manifest.json, "
                             "chunk_*.npz): write the result outside it")
    ext = os.path.splitext(output)[1].lower()
    if ext not in suffixes:
        raise ParameterError(f"{flag}: the extension decides the format: one of "
                             f"{', '.join(suffixes)}; got {output!r}")
    check_place(output, flag)


def check_not_input(output, data, source, what):
    """``data``, a file written beside ``output``, must not be the input ``source``, nor
    an existing folder.

    Parameters
    ----------
    output : str
        The output path the user gave (named in the message only).
    data : str
        The path of the file written beside ``output`` (e.g. ``OUTPUT.image.npz``).
    source : str
        The input's path.
    what : str
        What ``data`` holds, for the message (e.g. ``"image data"``).

    Raises
    ------
    ParameterError
        When ``data`` and ``source`` are one file (:func:`same_file`), or ``data`` is an
        existing folder; naming ``-o``.
    """
    if same_file(data, source):
        raise ParameterError(f"-o {output!r} would write the {what} to {data!r}, the "
                             "input: meshladar never overwrites an input; choose another "
                             "output name")
    if os.path.isdir(data):
        raise ParameterError(f"-o {output!r} would write the {what} to {data!r}, which is "
                             "a folder: choose another output name (or move the folder)")
