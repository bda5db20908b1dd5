"""Output paths the command line writes: never an input, always a known format."""

from __future__ import annotations

import os

from ..errors import ParameterError

__all__ = ["check_output", "check_outdir", "check_not_input", "same_file"]


def check_outdir(outdir):
    """An output folder: a folder (existing or not), not a file, not empty.

    Parameters
    ----------
    outdir : str or None
        The folder's path. It need not exist (the command creates it); nothing is created
        here.

    Raises
    ------
    ParameterError
        When ``outdir`` is empty or None, or names an existing path that is not a folder
        (a file).
    """
    if not outdir or (os.path.exists(outdir) and not os.path.isdir(outdir)):
        raise ParameterError(f"outdir must name a folder; got {outdir!r}"
                             + (" (a file)" if outdir and os.path.exists(outdir) else ""))


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


def check_output(output, suffixes, inputs, flag="-o"):
    """An output path must never name an input, and must name a file of a known format.

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

    Raises
    ------
    ParameterError
        When ``output`` is empty or None, names a folder (an existing one, or a path
        whose last component is empty, ``.`` or ``..``), is one of ``inputs``, or has an
        extension not in ``suffixes``.
    """
    if not output or os.path.basename(output) in ("", ".", "..") or os.path.isdir(output):
        raise ParameterError(f"{flag}: must name a file, not a folder; got {output!r}")
    for src in filter(None, inputs):
        if same_file(src, output):
            raise ParameterError(f"{flag} {output!r} is the input {src!r}: meshladar never "
                                 "overwrites an input; choose another output name")
    ext = os.path.splitext(output)[1].lower()
    if ext not in suffixes:
        raise ParameterError(f"{flag}: the extension decides the format: one of "
                             f"{', '.join(suffixes)}; got {output!r}")


def check_not_input(output, data, source, what):
    """``data``, a file written beside ``output``, must not be the input ``source``.

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
        When ``data`` and ``source`` are one file (:func:`same_file`).
    """
    if same_file(data, source):
        raise ParameterError(f"-o {output!r} would write the {what} to {data!r}, the "
                             "input: meshladar never overwrites an input; choose another "
                             "output name")
