"""Atomic file writes: the content goes to a temporary beside the target, is flushed and
fsynced, and is renamed over the target, so a crash never leaves a half-written file; on the
main thread, Ctrl-C and SIGTERM are held until the rename is done. The temporaries a killed
writer left behind are recognised by their name and removed by the next write into their
folder.

:mod:`meshladar.io` re-exports the public names (``meshladar.io.write_atomic``), where the
result files that use them are saved and loaded.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import stat
import tempfile
import threading

__all__ = ["write_atomic", "write_text_atomic", "TEMPORARY_PREFIX", "temporary_writer",
           "regular_file", "make_temporary"]

#: The prefix of the temporaries meshladar writes beside a file before renaming it into
#: place: ``.meshladar-tmp-<pid>-<8 random characters><final name>``. Only names of exactly
#: that form are ever cleaned up, so a user's own ``.tmp-…`` files are never touched.
TEMPORARY_PREFIX = ".meshladar-tmp-"
_TEMPORARY = re.compile(re.escape(TEMPORARY_PREFIX) + r"(\d{1,10})-[a-z0-9_]{8}.")


def temporary_writer(name: str):
    """The pid of the meshladar process that wrote temporary ``name``, or None when ``name``
    is not one of meshladar's temporaries.

    Parameters
    ----------
    name : str
        A file name (no folder): ``.meshladar-tmp-<pid>-<8 characters><final name>`` for
        one of meshladar's temporaries.

    Returns
    -------
    int or None
        The writer's process id, or None when ``name`` does not have that form.
    """
    match = _TEMPORARY.match(name)
    return int(match.group(1)) if match else None


def regular_file(path) -> bool:
    """True when ``path`` itself (not a link's target) is a regular file."""
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False


def _new_file_mode(path):
    """The permissions an ordinary ``open(path, "w")`` would give: the existing file's, or
    0o666 less the user's umask (mkstemp's temporaries are 0o600)."""
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        return 0o666 & ~_umask()


def _umask():
    """The process's umask, read without changing it where the system says it (Linux);
    elsewhere set and restored at once."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_atomic(path, write):
    """Write a file atomically: ``write(fh)`` fills a temporary beside ``path`` (binary
    mode), which is renamed over ``path`` once complete, with the user's normal
    permissions.

    The folder is created if missing; stale temporaries of dead meshladar processes in it
    are removed (once per folder and process). On the main thread, Ctrl-C and SIGTERM
    are held while the file is written and renamed, and delivered after (a second signal
    of a kind is delivered at once). The data is flushed and fsynced before the rename.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write; replaced if it exists (keeping its permissions; a new file gets
        0o666 less the umask).
    write : callable
        Called once with the temporary's binary file object; it writes the content.

    Raises
    ------
    OSError
        When the folder or temporary cannot be made or written (a full disk, a lost
        permission), naming ``path`` rather than the temporary. On any failure the
        temporary is removed and ``path`` is left as it was; an exception raised by
        ``write`` propagates.
    """
    _atomic(path, write)


def make_temporary(path):
    """Make the temporary that ``path``'s content is written into before it is renamed
    over ``path``: ``.meshladar-tmp-<pid>-<8 characters><name>`` beside it (the folder
    created if missing), with the permissions ``path`` will have. Stale temporaries of
    dead meshladar processes in the folder are removed first (once per folder and
    process), so one that a killed writer left is gone by the next write into its folder.

    :func:`write_atomic` writes through it; a writer that fills its file piece by piece
    (the scanner's streaming waveform file) opens the temporary by its name and renames
    it over ``path`` when done.

    Parameters
    ----------
    path : str or os.PathLike
        The file the temporary will replace.

    Returns
    -------
    fd : int
        The temporary's open file descriptor (the caller closes it).
    tmp : str
        The temporary's path.

    Raises
    ------
    OSError
        When the folder or the temporary cannot be made, naming ``path``.
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        os.makedirs(folder, exist_ok=True)
        _remove_stale_temporaries(folder)
        mode = _new_file_mode(path)
        # the writer's pid in the name: a temporary left by a killed process is recognised
        # (and removed) by the next process writing into the same folder
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f"{TEMPORARY_PREFIX}{os.getpid()}-",
                                   suffix=os.path.basename(path))
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, path) from exc
    try:
        os.fchmod(fd, mode)
    except OSError as exc:
        os.close(fd)
        os.unlink(tmp)
        raise OSError(exc.errno, exc.strerror, path) from exc
    return fd, tmp


def _atomic(path, write):
    path = os.fspath(path)
    fd, tmp = make_temporary(path)
    try:
        with _interrupts_held():
            with os.fdopen(fd, "wb") as fh:
                write(fh)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        interrupt = _interrupt_behind(exc)
        if interrupt is not None and interrupt is not exc:
            # Ctrl-C inside a writer that then failed to close (zipfile: "can't close the
            # ZIP file while there is an open writing handle"): the interrupt is the news
            raise interrupt from None
        if isinstance(exc, OSError) and getattr(exc, "filename", None) in (tmp, None):
            # a full disk or a lost permission: name the user's file, not the temporary
            raise OSError(exc.errno, exc.strerror or str(exc), path) from exc
        raise


#: The signals a file's write holds until the file is whole: Ctrl-C, and SIGTERM (which the
#: command line turns into an interrupt).
_HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def _interrupts_held():
    """Hold Ctrl-C and SIGTERM while a file is written, then deliver them: an interrupt
    that lands inside numpy's zip writer would leave a ZipFile that complains when it is
    collected, long after the clean stop. A second signal of a kind delivers it at once
    (a write that hangs can still be stopped). Off the main thread, and for handlers set
    outside Python, nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in _HELD_SIGNALS}
    held = [s for s, handler in previous.items() if handler not in (None, signal.SIG_IGN)]
    pending = []

    def hold(signum, frame):
        if signum in pending:                            # pressed again: now
            pending.remove(signum)
            signal.signal(signum, previous[signum])
            signal.raise_signal(signum)
        pending.append(signum)

    for signum in held:
        signal.signal(signum, hold)
    try:
        yield
    finally:
        for signum in held:
            signal.signal(signum, previous[signum])
        for signum in dict.fromkeys(pending):
            signal.raise_signal(signum)


def _interrupt_behind(exc):
    """The KeyboardInterrupt ``exc`` is, or was raised while handling, else None."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__context__
    return None


#: Folders already swept of stale temporaries by this process (once each: a run folder
#: of 1e5 chunks is listed once, not once per chunk).
_SWEPT: set = set()


def _remove_stale_temporaries(folder):
    """Remove meshladar's temporaries (:data:`TEMPORARY_PREFIX`) in ``folder`` whose writer
    is no longer alive: regular files of exactly that name form, nothing else."""
    if folder in _SWEPT:
        return
    _SWEPT.add(folder)
    try:
        entries = os.listdir(folder)
    except OSError:
        return
    for entry in entries:
        pid = temporary_writer(entry)
        if pid is None or _alive(pid) or not regular_file(os.path.join(folder, entry)):
            continue
        try:
            os.remove(os.path.join(folder, entry))
        except OSError:
            pass


def _alive(pid):
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                 # another user's process: alive
        return True
    return True


def write_text_atomic(path, text: str):
    """Write a text file atomically (UTF-8).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (as :func:`write_atomic`).
    text : str
        The content, encoded as UTF-8.

    Raises
    ------
    OSError
        As :func:`write_atomic`.
    """
    _atomic(path, lambda fh: fh.write(text.encode("utf-8")))
