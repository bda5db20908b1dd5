"""Resumable, loss-free runs: a run folder with a manifest and one verified file per chunk.

A long job (many views, a study, a material sweep) is split into chunks. With a run folder,
each finished chunk is written atomically as ``chunk_00012.npz`` holding its arrays and, in
its metadata, the SHA-256 of their bytes; ``manifest.json`` holds the job's full parameters
and meshladar's version. Re-running the same job in the same folder verifies every chunk file
(readable, checksum, shape) and reuses it; only missing or corrupt chunks are computed. A
different job pointed at the same folder is refused (:class:`RunFolderError`), never mixed;
so is a folder holding a file of a run folder's names that meshladar did not write
(:class:`ForeignFileError`): a run never overwrites a file it did not write.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
import warnings

import numpy as np

from ._run_files import (MANIFEST_MAX_BYTES, chunk_kind, jsonable as _jsonable, lock_is_ours,
                         manifest_kind, non_finite as _non_finite, owned as _owned, refusal)
from ._version import __version__
from .errors import MeshladarError, MeshladarWarning, ParameterError, user_stacklevel
from .io import (ResultFileError, load_result, regular_file, save_result, temporary_writer,
                 write_text_atomic)

__all__ = ["RunFolder", "RunFolderError", "ForeignFileError", "job_digest", "array_digest",
           "chunk_digest"]


class RunFolderError(MeshladarError, ValueError):
    """A run folder holds another job, or cannot be used.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


class ForeignFileError(RunFolderError, ParameterError):
    """The run folder holds a file of a run folder's names (``manifest.json``, a
    ``chunk_*.npz``, ``.lock``) that meshladar did not write: refused before any work, since
    a run would overwrite it. Also a :class:`~meshladar.errors.ParameterError`: ``run_dir``
    names the wrong folder.

    Parameters
    ----------
    *args : object
        The message (a ``str``), passed on to the builtin exception unchanged.
    """


def job_digest(job: dict) -> str:
    """A stable hash of a job description (JSON with sorted keys).

    Parameters
    ----------
    job : dict
        The job description; values JSON cannot encode are encoded as their ``str``.

    Returns
    -------
    str
        The SHA-256 of the job's JSON text (sorted keys, UTF-8), 64 hexadecimal digits.
    """
    return hashlib.sha256(json.dumps(job, sort_keys=True, default=str).encode()).hexdigest()


def array_digest(a) -> str:
    """The SHA-256 of one array's bytes (a job description's record of its large inputs).

    Parameters
    ----------
    a : array_like
        The array; hashed in C order. Its dtype and shape are not hashed (see
        :func:`chunk_digest`).

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


def chunk_digest(arrays: dict) -> str:
    """The SHA-256 of a chunk's named arrays (names, dtypes, shapes and bytes, in name
    order): the checksum a chunk file records and is verified against.

    Parameters
    ----------
    arrays : dict
        Names (str) to array_like values; each array is hashed in C order.

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(k.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


class RunFolder:
    """The run folder of one job: ``RunFolder(path, job, n_chunks)``.

    ``load(i)`` returns chunk i's arrays if its file exists and verifies, else None;
    ``save(i, arrays)`` writes it atomically.

    Opening one takes an exclusive lock on the folder (``.lock``, on POSIX systems; released
    by :meth:`close`, on leaving a ``with`` block, or when the process ends), checks the
    folder's own files, removes temporaries left by killed writes, and writes the manifest
    when there is none (or a damaged one) and no chunk of another job. Other files in the
    folder are never read or touched.

    A run never overwrites a file it did not write: before any work, a file under a run
    folder's names that is readably someone else's is refused (a ``manifest.json`` that is a
    JSON object with keys a manifest never has, a ``chunk_*.npz`` that is an ``.npz`` or zip
    without a chunk's metadata, a ``.lock`` holding other text). A file that cannot be read
    (a manifest that is not JSON, or JSON of another shape such as ``[]`` or ``{}``; a chunk
    that is not a readable ``.npz``) cannot tell whose it is, so the folder decides:
    beside the manifest or a chunk of this job it is meshladar's own, damaged, and is
    rewritten (the manifest) or recomputed (the chunk), as a resume must; in a folder with
    nothing of this job's it is refused. Meshladar writes these files atomically, so a
    damaged one comes from the disk or a hand, never from a killed run.

    Parameters
    ----------
    path : str or os.PathLike
        The run folder; created if missing.
    job : dict
        The job's full parameters (JSON-serialisable, anything else by its ``str``).
    n_chunks : int
        How many chunks the job has; added to ``job`` as ``n_chunks``.

    Attributes
    ----------
    path : str
        The run folder.
    n_chunks : int
        How many chunks the job has.
    job : dict
        ``job`` with ``n_chunks``.
    digest : str
        :func:`job_digest` of ``job``: what the manifest and every chunk file record.

    Raises
    ------
    RunFolderError
        When another run holds the folder's lock; the manifest names a different job; the
        manifest is missing or damaged and some readable chunk files belong to another
        job; or one of the folder's own files (``.lock``, ``manifest.json``, a chunk) is
        a link, a FIFO, a folder or a device, or cannot be opened.
    ForeignFileError
        (a RunFolderError and a :class:`~meshladar.errors.ParameterError`) When one of
        those names holds a file meshladar did not write, as above; the message names the
        file and says to choose an empty or new folder, or move the file away.
    """

    def __init__(self, path, job: dict, n_chunks: int):
        self.path = os.fspath(path)
        self.n_chunks = int(n_chunks)
        self.job = dict(job, n_chunks=self.n_chunks)
        self.digest = job_digest(self.job)
        os.makedirs(self.path, exist_ok=True)
        self._lock = _lock(self.path)
        try:
            self._start()
        except BaseException:
            self.close()
            raise

    def _start(self):
        """Check the folder's own files, then clean temporaries and write the manifest when
        it has none (or a damaged one), holding the lock: every refusal comes before any
        file is touched."""
        names = sorted(os.listdir(self.path))
        for name in names:
            if _owned(name):
                _check_regular(os.path.join(self.path, name))
        kind, old = self._manifest()
        if kind == "ours" and old["digest"] != self.digest:
            changed = sorted(k for k in set(old.get("job", {})) | set(self.job)
                             if old.get("job", {}).get(k) != _jsonable(self.job.get(k)))
            raise RunFolderError(
                f"{self.path}: this run folder holds a different job (differs in "
                f"{', '.join(changed[:5]) or 'its parameters'}); use another folder, or "
                "delete this one to start over")
        chunks = self._chunks(names)
        if kind != "ours":
            self._check_unproven(kind, old, chunks)
        # temporaries of writes cut short by a kill: never under a final name, removed here
        # (only while holding the lock, so never another run's in-flight files; only
        # meshladar's own names, regular files, never a user's file or a link)
        for name in names:
            full = os.path.join(self.path, name)
            if temporary_writer(name) is not None and regular_file(full):
                try:
                    os.remove(full)
                except OSError:
                    pass
        if kind != "ours":
            write_text_atomic(os.path.join(self.path, "manifest.json"), json.dumps(
                {"digest": self.digest, "job": _jsonable(self.job),
                 "meshladar_version": __version__}, indent=1, sort_keys=True))

    def _manifest(self):
        """The manifest's verdict (:func:`~meshladar._run_files.manifest_kind`), ``("absent",
        None)`` when there is none; someone else's manifest is refused here."""
        manifest = os.path.join(self.path, "manifest.json")
        if not os.path.lexists(manifest):
            return "absent", None
        with _open_plain(manifest, binary=True) as fh:
            try:
                raw = fh.read(MANIFEST_MAX_BYTES + 1)
            except OSError as exc:
                raw = None
                kind, old = "damaged", f"cannot be read ({exc.strerror})"
        if raw is not None:
            kind, old = manifest_kind(raw)
        if kind == "foreign":
            raise ForeignFileError(refusal(self.path, "manifest.json",
                                           f"not a meshladar run manifest ({old})"))
        return kind, old

    def _chunks(self, names):
        """Each chunk file's verdict by name (:func:`~meshladar._run_files.chunk_kind`);
        someone else's file under a chunk's name is refused here."""
        verdicts = {}
        for name in names:
            if name.startswith("chunk_") and name.endswith(".npz"):
                with _open_plain(os.path.join(self.path, name), binary=True) as fh:
                    kind, detail = verdicts[name] = chunk_kind(fh)
                if kind == "foreign":
                    raise ForeignFileError(refusal(self.path, name,
                                                   f"not a meshladar chunk ({detail})"))
        return verdicts

    def _check_unproven(self, kind, damage, chunks):
        """With no manifest of this job, the chunks must prove the folder this job's: one
        chunk of another job refuses it (never mixed), and a file that cannot be read (the
        manifest, a chunk) is taken for meshladar's own, damaged, only beside a chunk of this
        job; with none, whose it is cannot be told, and it is refused, never overwritten."""
        manifest = os.path.join(self.path, "manifest.json")
        foreign = sum(k == "chunk" and d != self.digest for k, d in chunks.values())
        if foreign:
            what = (f"{manifest}: unreadable manifest ({damage})" if kind == "damaged" else
                    f"{self.path}: no manifest")
            raise RunFolderError(f"{what}, and {foreign} chunk files belong to another "
                                 "job; use another folder")
        if any(k == "chunk" for k, _ in chunks.values()):
            return
        unknown = [(n, f"not a meshladar chunk ({d})") for n, (k, d) in chunks.items()
                   if k == "damaged"]
        if kind == "damaged":
            unknown.insert(0, ("manifest.json", f"not a meshladar run manifest ({damage})"))
        if unknown:
            name, what = unknown[0]
            raise ForeignFileError(refusal(self.path, name, f"{what}, and no chunk of this job "
                                           "beside it shows the folder is this run's"))

    def close(self):
        """Release the folder for other runs (also when this object is collected)."""
        lock, self._lock = getattr(self, "_lock", None), None
        if lock is not None:
            lock.close()

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _file(self, i):
        return os.path.join(self.path, f"chunk_{i:05d}.npz")

    def load(self, i, shapes=None):
        """Chunk i's arrays, or None when it is missing, unreadable, fails its checksum, was
        written for another chunk or job, holds non-finite numbers, or (with ``shapes``,
        name → expected shape) has arrays of other shapes: such a chunk is recomputed,
        never used (a warning names it when it was readable but wrong).

        Parameters
        ----------
        i : int
            The chunk's index.
        shapes : dict, optional
            Name → expected shape of the chunk's arrays (default None: not checked).

        Returns
        -------
        dict or None
            The chunk's arrays by name, or None when the chunk must be computed.

        Raises
        ------
        RunFolderError
            When the chunk's file is not a regular file (a link, a FIFO, a folder, a
            device).

        Warns
        -----
        MeshladarWarning
            When a chunk that verified holds NaN or inf in a floating or complex array.
        """
        f = self._file(i)
        if not os.path.lexists(f):
            return None
        _check_regular(f)
        try:
            arrays, meta = load_result(f)
        except ResultFileError:
            return None
        if (meta.get("job") != self.digest or meta.get("chunk") != int(i)
                or meta.get("sha256") != chunk_digest(arrays)):
            return None
        if shapes is not None and any(
                k not in arrays or arrays[k].shape != tuple(v) for k, v in shapes.items()):
            return None
        bad = _non_finite(arrays)
        if bad:
            warnings.warn(f"{f}: chunk {i} holds non-finite values in {bad!r}; recomputing it",
                          MeshladarWarning, stacklevel=user_stacklevel())
            return None
        return arrays

    def save(self, i, arrays: dict):
        """Write chunk i atomically; a chunk with non-finite numbers is refused (naming the
        chunk and the array), never kept to poison a resume.

        Parameters
        ----------
        i : int
            The chunk's index (file ``chunk_<i, 5 digits>.npz``).
        arrays : dict
            Names (str, not ``"__meta__"``) to numeric arrays; the file's metadata records
            the job's digest, ``i`` and :func:`chunk_digest` of them.

        Raises
        ------
        RunFolderError
            When a floating or complex array holds NaN or inf.
        ParameterError
            When a name is not a str or is ``"__meta__"``, or an array is of object dtype.
        """
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        bad = _non_finite(arrays)
        if bad:
            raise RunFolderError(f"{self._file(i)}: chunk {i} computed non-finite values in "
                                 f"{bad!r}; not kept (the inputs of that chunk are at fault)")
        save_result(self._file(i), arrays, {"job": self.digest, "chunk": int(i),
                                            "sha256": chunk_digest(arrays)})

    def done(self):
        """The chunks that have a file.

        Returns
        -------
        list of int
            The indices in [0, n_chunks) whose chunk file exists; the files are not
            verified here (:meth:`load` does that).
        """
        return [i for i in range(self.n_chunks) if os.path.exists(self._file(i))]


def _lock(path):
    """An exclusive lock on the run folder (``.lock``, flock: released by the OS when the
    process ends, however it ends); a folder in use by another run is refused."""
    try:
        import fcntl
    except ImportError:                          # not POSIX: no locking
        return None
    fh = _open_plain(os.path.join(path, ".lock"), create=True)
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.seek(0)
        holder = fh.read().strip() or "another process"
        fh.close()
        raise RunFolderError(f"{path}: run folder in use by another run ({holder}); wait for "
                             "it to finish, or use another folder") from None
    fh.seek(0)
    if not lock_is_ours(fh):
        fh.close()
        raise ForeignFileError(refusal(path, ".lock", "a lock file of another program (not "
                                       "empty, nor a process id)"))
    fh.seek(0)
    fh.truncate()
    fh.write(f"pid {os.getpid()}")
    fh.flush()
    return fh


def _check_regular(path):
    """Refuse, at once, a run-folder file that is a link, a FIFO, a folder or a device:
    meshladar's own files are regular files, and anything else would be followed (a link's
    target overwritten) or block forever (a FIFO)."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISREG(mode):
        kind = ("a symbolic link" if stat.S_ISLNK(mode) else "a FIFO" if stat.S_ISFIFO(mode)
                else "a folder" if stat.S_ISDIR(mode) else "not a regular file")
        raise RunFolderError(f"{path}: {kind} where the run folder keeps its own file; "
                             "remove it, or use another folder")


def _open_plain(path, create=False, binary=False):
    """Open a run-folder file for reading (and, with ``create``, writing; text, or bytes with
    ``binary``) without following a link, without blocking on a FIFO, and only if it is a
    regular file."""
    _check_regular(path)
    flags = os.O_NOFOLLOW | os.O_NONBLOCK | (os.O_RDWR | os.O_CREAT if create else os.O_RDONLY)
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        raise RunFolderError(f"{path}: cannot be opened ({exc.strerror}); remove it, or use "
                             "another folder") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):        # swapped in since the check
        os.close(fd)
        _check_regular(path)
        raise RunFolderError(f"{path}: not a regular file; remove it, or use another folder")
    os.set_blocking(fd, True)
    if binary:
        return os.fdopen(fd, "r+b" if create else "rb")
    return os.fdopen(fd, "r+" if create else "r", encoding="utf-8")
