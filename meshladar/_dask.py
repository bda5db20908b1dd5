"""A Dask client with a deadline (:func:`meshladar.stream.dask_executor`'s connection)."""

from __future__ import annotations

import threading

__all__ = ["connect"]


def connect(client_class, address, timeout, security):
    """A Dask client of the scheduler at ``address``, or TimeoutError once ``timeout`` (and
    a grace of a few seconds) has passed: distributed's own timeout does not cover a server
    that accepts the connection and never answers its handshake. A client that connects
    after the deadline is closed."""
    box, done, late = {}, threading.Event(), threading.Event()

    def attempt():
        try:
            box["client"] = client_class(address, timeout=timeout, security=security)
        except BaseException as exc:             # noqa: BLE001 - handed to the caller
            box["error"] = exc
        done.set()
        if late.is_set() and "client" in box:
            box["client"].close()

    threading.Thread(target=attempt, daemon=True, name="meshladar-dask-connect").start()
    if not done.wait(timeout + _CONNECT_GRACE_S):
        late.set()
        if done.is_set() and "client" in box:   # it made it just now after all
            box["client"].close()
        raise TimeoutError(f"no handshake in {timeout + _CONNECT_GRACE_S:g} s")
    if "error" in box:
        raise box["error"]
    return box["client"]


#: Seconds allowed beyond the scheduler timeout for the client's own start-up.
_CONNECT_GRACE_S = 5.0
