"""The ``meshladar`` command line.

Errors from bad input print one line (``meshladar: error: ...``) and exit with status 2;
they never show a traceback. Layout: :mod:`.parser` (generated from
:mod:`meshladar.forward.options` for ``simulate``), :mod:`.argtypes` (the flags' value checkers),
:mod:`.checks` (output paths), and the command bodies in :mod:`.simulate`,
:mod:`.reconstruct` (``reconstruct``, ``receive``) and :mod:`.commands` (the rest); each
body only calls the API.
"""

from __future__ import annotations

import functools
import os
import re
import signal
import sys
import tempfile
import threading
import traceback
import warnings

from ..errors import MeshladarError
from .commands import (cmd_bench, cmd_demo, cmd_materials, cmd_paper, cmd_study, cmd_view,
                       view_words)
from .parser import build_parser
from .reconstruct import cmd_receive, cmd_reconstruct, receive_words, reconstruct_words
from .lrcs import cmd_lrcs, lrcs_words
from .scan import cmd_scan, scan_words
from .simulate import cmd_simulate, in_flags

__all__ = ["main", "COMMANDS"]

#: Each command's function, looked up when the command runs.
COMMANDS = {"demo": cmd_demo, "materials": cmd_materials, "paper": cmd_paper,
            "simulate": cmd_simulate, "reconstruct": cmd_reconstruct,
            "receive": cmd_receive, "scan": cmd_scan, "lrcs": cmd_lrcs, "view": cmd_view,
            "study": cmd_study, "bench": cmd_bench}


def _one_line_warning(message, category, filename, lineno, line=None, *, words=str):
    return f"meshladar: warning: {words(str(message))}\n"


#: Per command, how an API message (an error's or a warning's) is put in its flags' words
#: (simulate's: ``normals='smooth'`` becomes ``--normals smooth``, ``ray_spacing``
#: ``--ray-spacing``; :mod:`.words`): the one place the command's messages are translated.
_WORDS = {"simulate": in_flags, "lrcs": lrcs_words, "receive": receive_words,
          "reconstruct": reconstruct_words, "scan": scan_words, "view": view_words}


def main(argv=None) -> int:
    """Run the command line; returns the exit status.

    Errors never show a traceback: an input error prints one ``meshladar: error: ...``
    line, and a bug of meshladar's own prints one line naming a file that holds the
    traceback. Warnings print as one ``meshladar: warning: ...`` line each (simulate's in
    its flags' words) while the command runs; the caller's ``warnings.formatwarning`` is
    restored afterwards. On the main thread SIGTERM stops a run as Ctrl-C does, and the
    previous SIGTERM handler is restored afterwards.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program's name, e.g. ``["simulate", "disk", "-o",
        "disk.npz"]``. Default None: ``sys.argv[1:]`` (argparse's default).

    Returns
    -------
    int
        The exit status: the command's own (0 on success); 2 for a
        :class:`~meshladar.errors.MeshladarError` (its message in the command's flags'
        words), an ``ImportError`` (a missing extra) or an ``OSError``; 128 + the signal's
        number when interrupted (130 for Ctrl-C, 143 for SIGTERM on the main thread), with
        a hint to resume when ``--run-dir`` was given or a faceting study was running; 1
        for any other exception (a bug), its traceback written to a new temporary file
        ``meshladar-traceback-*.txt``.

    Raises
    ------
    SystemExit
        From argparse, before any command runs: status 2 for a command line it cannot
        parse (a flag's value checker's message), 0 after ``--help`` or ``--version``.
    """
    args = build_parser(COMMANDS).parse_args(argv)
    stop = _Stop()
    previous = _terminate_as_interrupt(stop)
    words = _kept_paths(_WORDS.get(args.command, str), args)
    format_before = warnings.formatwarning
    warnings.formatwarning = functools.partial(_one_line_warning, words=words)
    try:
        return COMMANDS[args.command](args)
    except MeshladarError as exc:
        print(f"meshladar: error: {words(str(exc))}", file=sys.stderr)
        return 2
    except ImportError as exc:                  # a missing extra, named there
        print(f"meshladar: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        print(f"meshladar: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"meshladar: interrupted{_resume_hint(args)}", file=sys.stderr)
        return 128 + stop.signum
    except Exception as exc:  # noqa: BLE001 - a bug of meshladar's own: say so in one line
        path = _save_traceback()
        print(f"meshladar: internal error ({type(exc).__name__}: "
              f"{' '.join(str(exc).split())[:200]}); this is a bug in meshladar, please "
              f"report it with the traceback in {path}", file=sys.stderr)
        return 1
    finally:
        warnings.formatwarning = format_before           # a caller's own is left as it was
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _kept_paths(words, args):
    """``words`` (a command's translator, :data:`_WORDS`) that keeps the command's own
    paths as typed: every argument that names an existing file or folder, or holds a dot
    or a separator (``seed=3/x.npz``, a file named ``oversample``), is set aside where it
    stands whole (not inside a longer name) before the translation and put back after."""
    paths = sorted({v for v in vars(args).values() if isinstance(v, str) and v and (
        os.path.exists(v) or "." in v or os.sep in v)}, key=len, reverse=True)
    if not paths:
        return words
    whole = [re.compile(r"(?<![\w./\\-])" + re.escape(p) + r"(?![\w/\\])") for p in paths]

    def kept(message):
        for i, path in enumerate(whole):
            message = path.sub(f"\x00{i}\x00", message)
        message = words(message)
        for i, path in enumerate(paths):
            message = message.replace(f"\x00{i}\x00", path)
        return message

    return kept


def _save_traceback():
    """Write the current exception's traceback to a new file; return its path."""
    fd, path = tempfile.mkstemp(prefix="meshladar-traceback-", suffix=".txt")
    with open(fd, "w", encoding="utf-8") as fh:
        traceback.print_exc(file=fh)
    return path


def _resume_hint(args):
    """What an interrupted command kept, and how to go on: a run folder's finished chunks,
    a faceting study's finished points (in OUTDIR/run); the other studies keep nothing."""
    if getattr(args, "run_dir", None):
        return (f"; finished chunks are kept in {args.run_dir}: run the same command again "
                "to resume")
    if args.command == "study" and args.kind == "faceting":
        return (f"; finished study points are kept in {os.path.join(args.outdir, 'run')}: "
                "run the same command again to resume")
    if args.command == "study":
        return (f"; the {args.kind} study keeps no finished part: running it again starts "
                "over")
    return ""


class _Stop:
    """The signal that stopped the command: SIGINT (Ctrl-C) unless SIGTERM's handler ran.
    Called as SIGTERM's handler, it records the signal and stops the run as Ctrl-C does."""

    def __init__(self):
        self.signum = int(signal.SIGINT)

    def __call__(self, signum, frame):
        self.signum = int(signum)
        raise KeyboardInterrupt


def _terminate_as_interrupt(stop):
    """SIGTERM stops a run as Ctrl-C does (workers cancelled, finished chunks kept, a
    resume hint), ``stop`` recording it; returns the previous handler, or None off the main
    thread."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGTERM, stop)
