"""Simulated file-system faults for writes under one folder: no space left, permission denied, read-only,
and a rival writer ('rival': another process creates the new folder this one is about to rename into place).

Tests run as root, for whom ``chmod`` does not stop a write, and no tiny file system can be
mounted; so the faults are injected where Python opens files for writing: ``os.open``,
``open``/``io.open`` and ``os.mkdir`` refuse (EACCES, EROFS), or writes to an opened file
fail (ENOSPC). The file-size limit (EFBIG) is real: ``RLIMIT_FSIZE`` in a child process.
"""
from __future__ import annotations

import builtins
import contextlib
import errno
import io
import os
from pathlib import Path

_WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC


def _under(path, folder) -> bool:
    try:
        return Path(os.fspath(path)).resolve().is_relative_to(folder)
    except (TypeError, ValueError, OSError):
        return False


class _FullDisk:
    """A file object whose writes fail with ENOSPC (opening worked, as on a full disk)."""

    def __init__(self, f, name):
        self._f, self._name = f, name

    def write(self, data):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), self._name)

    writelines = write

    def __getattr__(self, attr):
        return getattr(self._f, attr)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._f.close()

    def __iter__(self):
        return iter(self._f)


RIVAL_TEXT = b"the rival writer's bag\n"  # what the rival writes into the folder it creates (metadata.yaml)


@contextlib.contextmanager
def _rival(folder):
    """Just before a temporary folder under ``folder`` is renamed onto a name that does not exist, a rival makes
    that name (a bag folder of its own), as a second ``crfmap simulate`` into the same new folder would."""
    real_replace = os.replace

    def replace(src, dst, *args, **kw):
        if _under(dst, folder) and Path(src).is_dir() and not os.path.lexists(dst):
            os.mkdir(dst)
            Path(dst, "metadata.yaml").write_bytes(RIVAL_TEXT)
        return real_replace(src, dst, *args, **kw)

    os.replace = replace
    try:
        yield
    finally:
        os.replace = real_replace


@contextlib.contextmanager
def fault(kind, folder):
    """Inside the block, writes under ``folder`` fail as ``kind`` ('enospc', 'eacces', 'erofs') says
    ('rival': a rival writer creates the new folder first)."""
    if kind is None:
        yield
        return
    if kind == "rival":
        with _rival(Path(folder).resolve()):
            yield
        return
    folder = Path(folder).resolve()
    code = {"enospc": errno.ENOSPC, "eacces": errno.EACCES, "erofs": errno.EROFS}[kind]
    real_os_open, real_open, real_mkdir = os.open, builtins.open, os.mkdir

    def refuse(path):
        raise OSError(code, os.strerror(code), os.fspath(path))

    def os_open(path, flags, *args, **kw):
        if kind != "enospc" and flags & _WRITE_FLAGS and _under(path, folder):
            refuse(path)
        return real_os_open(path, flags, *args, **kw)

    def open_(file, mode="r", *args, **kw):
        writing = isinstance(file, (str, bytes, os.PathLike)) and any(c in mode for c in "wax+")
        if writing and _under(file, folder):
            if kind != "enospc":
                refuse(file)
            return _FullDisk(real_open(file, mode, *args, **kw), os.fspath(file))
        return real_open(file, mode, *args, **kw)

    def mkdir(path, *args, **kw):
        if kind != "enospc" and _under(path, folder):
            refuse(path)
        return real_mkdir(path, *args, **kw)

    os.open, builtins.open, io.open, os.mkdir = os_open, open_, open_, mkdir
    try:
        yield
    finally:
        os.open, builtins.open, io.open, os.mkdir = real_os_open, real_open, real_open, real_mkdir
