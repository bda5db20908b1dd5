"""The command line's entry point: ``python -m meshladar`` and the ``meshladar`` script
(:func:`script`; :func:`run` for a caller in the same process).

The command line imports the whole engine (about a second); a Ctrl-C or SIGTERM during that
import is one line and status 130 (Ctrl-C) or 143 (SIGTERM), like one during a run, not a
traceback from inside whichever module was loading. The import stands at the top of this
module, under the guard.
"""

import os
import signal
import sys


#: The signal that interrupted the import, if one did (SIGTERM; a Ctrl-C raises by itself).
_stopped_by = []


def _interrupt(signum, frame):
    _stopped_by.append(int(signum))
    raise KeyboardInterrupt


_previous = signal.signal(signal.SIGTERM, _interrupt)
try:
    from .cli import main
except KeyboardInterrupt:
    main = None                      # interrupted while loading: run() says so
finally:
    signal.signal(signal.SIGTERM, _previous)


def run(argv=None) -> int:
    """Run the command line with ``argv`` (default the process's).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program's name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        :func:`meshladar.cli.main`'s status; when loading the command line was interrupted,
        128 + the signal's number (130 for Ctrl-C, 143 for SIGTERM) after one line.
    """
    if main is None:
        print("meshladar: interrupted", file=sys.stderr)
        return 128 + (_stopped_by[-1] if _stopped_by else int(signal.SIGINT))
    return main(argv)


def script(argv=None):
    """The ``meshladar`` script and ``python -m meshladar``: :func:`run`, then the process
    ends at once with its status. By then every file is written and closed and every
    thread, worker and Dask cluster joined or closed, so the interpreter's teardown (0.1 to
    0.2 s of freeing the engine's modules and arrays, at the end of every command) is
    skipped; the output streams are flushed first. An exception (argparse's exit after
    ``--help`` or a bad flag) ends the process as usual."""
    status = run(argv)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):            # a closed pipe: nothing left to say
            pass
    os._exit(status if isinstance(status, int) else 1)


if __name__ == "__main__":
    script()
