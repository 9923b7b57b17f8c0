"""Write files so that nothing is ever half-written: a temporary file, then a rename."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    On an exception the temporary file is removed and ``path`` is left untouched.

    >>> with atomic_path("out.txt") as tmp:  # doctest: +SKIP
    ...     Path(tmp).write_text("done")
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        _set_new_file_mode(tmp, path)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(tmp)
        raise


@contextlib.contextmanager
def atomic_dir(path):
    """Like :func:`atomic_path` for a folder (a ROS2 bag is a folder)."""
    import shutil

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    tmp.rmdir()  # writers such as rosbags' refuse an existing folder
    try:
        yield tmp
        _set_new_file_mode(tmp, path, folder=True)
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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
    """Give ``tmp`` the mode ``path`` has (when replacing it), else 0666 (folders 0777) minus the umask.

    map_saver, numpy and rosbag2 create files with plain open()/mkdir(), i.e. this mode;
    mkstemp/mkdtemp's private 0600/0700 would hide maps and figures from other users and services.
    """
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
