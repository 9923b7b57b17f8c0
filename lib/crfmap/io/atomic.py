"""Write files so that nothing is ever half-written: a temporary file, then a rename.

While a temporary exists, SIGTERM and SIGHUP (like SIGINT) raise :class:`Interrupted` in the main thread, so the
clean-up removes it (their default action would kill the process and leave ``.name.xxxx.tmp`` behind)."""
from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path
import sqlite3

CAUGHT_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


class Interrupted(KeyboardInterrupt):
    """A termination signal arrived (``signum``); raised so that clean-up code runs."""

    def __init__(self, signum):
        self.signum = int(signum)
        super().__init__(f"interrupted by {signal.Signals(signum).name}")


def _raise_interrupted(signum, frame):
    raise Interrupted(signum)


@contextlib.contextmanager
def signals_raise():
    """Inside the block, SIGTERM and SIGHUP raise :class:`Interrupted` (main thread; handlers set by others are kept).

    >>> with signals_raise():
    ...     pass
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for sig in CAUGHT_SIGNALS:
        if signal.getsignal(sig) in (signal.SIG_DFL, None):
            previous[sig] = signal.signal(sig, _raise_interrupted)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


@contextlib.contextmanager
def _signals_deferred():
    """Hold SIGTERM/SIGHUP/SIGINT back while a temporary is created and registered for clean-up: the handlers only note
    a signal, and the one in force runs after the block (``pthread_sigmask`` is not enough: another thread, e.g.
    numba's, may take the signal and Python still runs the handler in the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []
    previous = {sig: signal.signal(sig, lambda signum, frame: pending.append(signum))
                for sig in (*CAUGHT_SIGNALS, signal.SIGINT)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if pending:
            handler = previous[pending[0]]
            if callable(handler):
                handler(pending[0], None)  # e.g. _raise_interrupted or Python's KeyboardInterrupt
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), pending[0])


_RECORDERS = []  # lists that record_written() blocks collect each completed write's targets in


@contextlib.contextmanager
def record_written():
    """Yields a list of the targets of every write completed in the block, so a later failure can say what was written.

    >>> with record_written() as written:
    ...     pass
    >>> written
    []
    """
    written = []
    _RECORDERS.append(written)
    try:
        yield written
    finally:
        _RECORDERS.remove(written)


def _completed(*paths):
    for written in _RECORDERS:
        written.extend(Path(p) for p in paths)


def _named(exc, path):
    """A write failure as an OSError naming ``path`` (a failed write(2) or a storage library names no file)."""
    if isinstance(exc, OSError) and exc.filename is None:
        if exc.errno is None:  # numpy's short write: "N requested and M written"
            return OSError(errno.EIO, f"write failed, nothing was written ({exc}: disk full or file-size limit?)",
                           str(path))
        return OSError(exc.errno, exc.strerror or str(exc), str(path))
    if isinstance(exc, sqlite3.Error):  # rosbags' ROS 2 storage: e.g. "disk I/O error" on a full disk
        return OSError(errno.EIO, f"cannot write ({exc})", str(path))
    return None


def _check_target(path: Path):
    if path.is_dir() and not path.is_symlink():
        raise IsADirectoryError(21, "is a folder, expected a file name", str(path))


@contextlib.contextmanager
def unit_lock(folder, exclusive):
    """An advisory flock on ``folder`` itself (no lock file left behind): writers of a multi-file unit hold it
    exclusively while renaming, readers share it while reading."""
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        yield  # a folder we cannot open: no lock (nothing can be written there either)
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        except OSError:
            pass  # a file system without locks (some network mounts): write/read unlocked, as before
        yield
    finally:
        os.close(fd)  # closing releases the lock


@contextlib.contextmanager
def atomic_paths(*paths):
    """Yield temporary paths beside ``paths``; on success rename them all as one unit under :func:`unit_lock`; on an
    exception (or SIGTERM/SIGHUP/SIGINT) remove every temporary, leaving the targets untouched."""
    paths = [Path(p) for p in paths]
    for path in paths:
        _check_target(path)
    tmps = []
    with signals_raise():
        try:
            for path in paths:
                path.parent.mkdir(parents=True, exist_ok=True)
                with _signals_deferred():
                    fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:200]}.", suffix=".tmp", dir=path.parent)
                    os.close(fd)
                    tmps.append(Path(tmp))
            yield tmps if len(paths) > 1 else tmps[0]
            for tmp, path in zip(tmps, paths):
                _set_new_file_mode(tmp, path)
            with unit_lock(paths[0].parent, exclusive=True):
                for tmp, path in zip(tmps, paths):
                    os.replace(tmp, path)
            _completed(*paths)
        except BaseException as exc:
            for tmp in tmps:
                with contextlib.suppress(FileNotFoundError):
                    os.remove(tmp)
            named = _named(exc, paths[0])
            if named is not None:
                raise named from None
            raise


def atomic_path(path):
    """:func:`atomic_paths` of one file: yield a temporary path beside ``path``, renamed onto it on success."""
    return atomic_paths(path)


def is_bag_folder(path) -> bool:
    """Whether folder ``path`` looks like a ROS 2 bag (it has a metadata.yaml)."""
    return (Path(path) / "metadata.yaml").is_file()


@contextlib.contextmanager
def atomic_dir(path):
    """Like :func:`atomic_path` for a folder (a ROS 2 bag). An existing ``path`` is replaced only if it is empty or a
    ROS 2 bag; one that appeared while writing (another writer's) is never replaced: FileExistsError naming it."""
    path = Path(path)
    existed = path.exists() or path.is_symlink()
    if path.exists() and not (path.is_dir() and (is_bag_folder(path) or not any(path.iterdir()))):
        raise FileExistsError(17, "exists and is not a ROS 2 bag folder (or empty); not replacing it", str(path))
    with signals_raise():
        path.parent.mkdir(parents=True, exist_ok=True)
        # written as <hidden temporary>/<final name>: writers name their files after the folder (name_0.db3)
        box = None
        try:
            with _signals_deferred():  # inside the try: a deferred signal raises where the clean-up sees box
                box = Path(tempfile.mkdtemp(prefix=f".{path.name[:200]}.", suffix=".tmp", dir=path.parent))
            tmp = box / path.name
            yield tmp
            _set_new_file_mode(tmp, path, folder=True)
            # check and rename under one lock: of two writers of one new folder, the second refuses
            with unit_lock(path.parent, exclusive=True):
                if not existed and (path.exists() or path.is_symlink()):
                    raise FileExistsError(17, "was created by another process while this one was writing it; "
                                              "not replacing it", str(path))
                if path.exists():
                    os.replace(path, box / ".old")  # moved aside first: a failed rename then puts it back
                    try:
                        os.replace(tmp, path)
                    except BaseException:
                        os.replace(box / ".old", path)
                        raise
                else:
                    os.replace(tmp, path)
            _completed(path)
        except BaseException as exc:
            named = _named(exc, path)
            if named is not None:
                raise named from None
            raise
        finally:
            if box is not None:
                shutil.rmtree(box, ignore_errors=True)


# --- permissions: what open()/mkdir() would give, not mkstemp's 0600 --------------------------
def current_umask() -> int:
    """The process umask (read from /proc where possible: setting it to probe is not thread-safe).

    >>> 0 <= current_umask() <= 0o777
    True
    """
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _set_new_file_mode(tmp, path, folder=False):
    """Give ``tmp`` the mode ``path`` has (when replacing it), else 0666 (folders 0777) minus the umask, as
    map_saver's and rosbag2's plain open()/mkdir() do (mkstemp's 0600 would hide maps from other users)."""
    tmp = Path(tmp)
    if not tmp.exists():
        return
    try:
        mode = os.stat(path).st_mode & 0o7777 if Path(path).is_dir() == folder else None
    except OSError:
        mode = None
    if mode is None:
        mode = (0o777 if folder else 0o666) & ~current_umask()
    os.chmod(tmp, mode)
