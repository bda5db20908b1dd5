"""A minimal progress bar for long runs: on a terminal only, silent otherwise."""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """``Progress(total, unit, enabled=True)``; ``update(n)``; ``close()``.

    Draws to stderr only when enabled and stderr is a TTY (quiet in pipes, logs and CI).
    """

    def __init__(self, total, unit="items", *, enabled=True, stream=None):
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(enabled) and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.total, self.unit, self.done = int(total), unit, 0
        self.start = time.monotonic()
        self._last = 0.0

    def update(self, n=1):
        self.done += n
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last < 0.1 and self.done < self.total:
            return
        self._last = now
        frac = self.done / max(self.total, 1)
        bar = "#" * int(30 * frac)
        rate = self.done / max(now - self.start, 1e-9)
        eta = (self.total - self.done) / rate if rate > 0 else 0.0
        self.stream.write(f"\r[{bar:<30}] {self.done}/{self.total} {self.unit} "
                          f"{rate:.1f}/s eta {eta:.0f}s")
        self.stream.flush()

    def close(self):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
