"""The command line's entry point: ``python -m meshladar`` and the ``meshladar`` script.

The command line imports the whole engine (about a second); a Ctrl-C or SIGTERM during that
import is one line and status 130, like one during a run, not a traceback from inside
whichever module was loading. The import stands at the top of this module, under the guard.
"""

import signal
import sys


def _interrupt(signum, frame):
    raise KeyboardInterrupt


_previous = signal.signal(signal.SIGTERM, _interrupt)
try:
    from .cli import main
except KeyboardInterrupt:
    main = None                      # interrupted while loading: run() says so
finally:
    signal.signal(signal.SIGTERM, _previous)


def run(argv=None) -> int:
    """Run the command line with ``argv`` (default the process's)."""
    if main is None:
        print("meshladar: interrupted", file=sys.stderr)
        return 130
    return main(argv)


if __name__ == "__main__":
    raise SystemExit(run())
