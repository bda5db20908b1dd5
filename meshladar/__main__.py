"""The command line's entry point: ``python -m meshladar`` and the ``meshladar`` script.

The command line imports the whole engine (about a second); a Ctrl-C or SIGTERM during that
import is one line and status 130, like one during a run, not a traceback from inside
whichever module was loading.
"""

import signal
import sys


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def run(argv=None) -> int:
    """Import the command line, then run it with ``argv`` (default the process's)."""
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        from .cli import main        # heavy: under the guard below (a lazy door)
    except KeyboardInterrupt:
        print("meshladar: interrupted", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)
    return main(argv)


if __name__ == "__main__":
    raise SystemExit(run())
