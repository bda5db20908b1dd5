"""Output paths the command line writes: never an input, always a known format."""

from __future__ import annotations

import os

from ..errors import ParameterError

__all__ = ["check_output", "check_outdir", "check_not_input"]


def check_outdir(outdir):
    """An output folder: a folder (existing or not), not a file, not empty."""
    if not outdir or (os.path.exists(outdir) and not os.path.isdir(outdir)):
        raise ParameterError(f"outdir must name a folder; got {outdir!r}"
                             + (" (a file)" if outdir and os.path.exists(outdir) else ""))


def check_output(output, suffixes, inputs, flag="-o"):
    """An output path must never name an input, and must name a file of a known format."""
    if not output or os.path.basename(output) in ("", ".", "..") or os.path.isdir(output):
        raise ParameterError(f"{flag}: must name a file, not a folder; got {output!r}")
    for src in filter(None, inputs):
        if os.path.abspath(src) == os.path.abspath(output) or (
                os.path.exists(src) and os.path.exists(output)
                and os.path.samefile(src, output)):
            raise ParameterError(f"{flag} {output!r} is the input {src!r}: meshladar never "
                                 "overwrites an input; choose another output name")
    ext = os.path.splitext(output)[1].lower()
    if ext not in suffixes:
        raise ParameterError(f"{flag}: the extension decides the format: one of "
                             f"{', '.join(suffixes)}; got {output!r}")


def check_not_input(output, data, source, what):
    """``data``, a file written beside ``output``, must not be the input ``source``."""
    if os.path.abspath(data) == os.path.abspath(source) or (
            os.path.exists(data) and os.path.samefile(data, source)):
        raise ParameterError(f"-o {output!r} would write the {what} to {data!r}, the "
                             "input: meshladar never overwrites an input; choose another "
                             "output name")
