"""The environment variables crfmap reads, each checked where it is read: errors name the variable.

=====================  ===============================  ===========================================
variable               read by                          accepted
=====================  ===============================  ===========================================
``CRFMAP_ROOT``        :mod:`crfmap.data`, crfstudy.paths  an existing folder (the checkout; tests use a copy)
``CRFMAP_DATA``        :func:`crfmap.data.data_root`   a folder (missing files are named when needed)
``CRFMAP_MAX_CELLS``   :func:`crfmap.checks.max_cells`  a whole number >= 1 (``4e8`` too); no "no limit"
``NUMBA_NUM_THREADS``  numba, when it is imported       a whole number from 1 to the usable cores (checked then)
``NUMBA_CACHE_DIR``    numba, :mod:`crfmap._numba_cache` a folder numba can write (existing or not)
``OMP_WAIT_POLICY``    OpenMP (numba's parallel loops)  set to ``PASSIVE`` by :func:`prepare` unless set
=====================  ===============================  ===========================================

``OMP_WAIT_POLICY=PASSIVE``: OpenMP's threads otherwise spin after each parallel loop, taking a core from the threads
crfmap's other kernels run on and from other processes on the machine. A folder variable set but empty is refused (an
empty path would mean the working directory); an empty number variable means unset (the shell idiom
``VAR= command``), as numba reads its own. ``XDG_CACHE_HOME``, ``JPY_SESSION_NAME`` and ``MPLBACKEND`` are only
hints: a bad value falls back to the default.
"""
from __future__ import annotations

import math
import os
import re
import tempfile
from pathlib import Path

from crfmap.errors import InputError

_WHOLE = re.compile(r"\s*[+]?\d+\s*\Z")


def named_value(variable, text) -> str:
    """``variable=text`` as an error names it, a long value cut."""
    return f"{variable}={text}" if len(text) <= 80 else f"{variable}={text[:75]}[...]"


def folder(variable, default=None, must_exist=False) -> Path | None:
    """``$variable`` as a folder path, or ``default`` when it is unset.

    >>> os.environ["CRFMAP_EXAMPLE"] = ""
    >>> folder("CRFMAP_EXAMPLE")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: CRFMAP_EXAMPLE: is set but empty (unset it for the default, or name a folder)
    >>> del os.environ["CRFMAP_EXAMPLE"]
    """
    text = os.environ.get(variable)
    if text is None:
        return None if default is None else Path(default)
    if not text.strip():
        raise InputError(variable, "is set but empty (unset it for the default, or name a folder)")
    path = Path(text).expanduser()
    if path.exists() and not path.is_dir():
        raise InputError(named_value(variable, text), "is not a folder")
    if must_exist and not path.is_dir():
        raise InputError(named_value(variable, text), "no such folder")
    return path


def writable_folder(path, variable) -> Path:
    """``path`` if a file can be created in it (or in its nearest existing parent, where it will be made), probed with
    an unnamed temporary file; errors name ``variable`` (the setting that chose the folder) with its value."""
    path = Path(path)
    given = os.environ.get(variable)
    source = named_value(variable, given) if given else f"{path} (unset {variable}: its default)"
    probe = path
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        raise InputError(source, f"{probe} is not a folder")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        where = f"{path}" if probe == path else f"{path} (in {probe})"
        raise InputError(source, f"cannot write {where}: {exc.strerror or exc}") from None
    return path


def whole_number(variable, text, what, low=1) -> int:
    """``text`` (an environment value or an option) as a whole number >= ``low``; ``4e8`` is accepted.

    >>> whole_number("CRFMAP_MAX_CELLS", "4e8", "cells")
    400000000
    >>> whole_number("CRFMAP_MAX_CELLS", "1e400", "cells")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: CRFMAP_MAX_CELLS=1e400: expected a finite whole number of cells, got infinity
    """
    text = str(text)
    if _WHOLE.match(text):  # digits: exact, however long
        value = int(text)
        if value < low:
            raise InputError(named_value(variable, text), f"must be at least {low}")
        return value
    try:
        value = float(text)
    except ValueError:
        raise InputError(named_value(variable, text), f"expected a whole number of {what}") from None
    if not math.isfinite(value):
        raise InputError(named_value(variable, text), f"expected a finite whole number of {what}, got "
                         f"{'infinity' if math.isinf(value) else 'not-a-number'}")
    if value != int(value):
        raise InputError(named_value(variable, text), f"expected a whole number of {what}")
    if value < low:
        raise InputError(named_value(variable, text), f"must be at least {low}")
    return int(value)


def numba_threads() -> int | None:
    """``$NUMBA_NUM_THREADS`` checked (None: unset or empty, numba's own default)."""
    text = os.environ.get("NUMBA_NUM_THREADS", "")
    if not text.strip():
        return None
    if not _WHOLE.match(text):
        raise InputError(named_value("NUMBA_NUM_THREADS", text), "expected a whole number of threads >= 1")
    value = int(text)
    if value < 1:
        raise InputError(named_value("NUMBA_NUM_THREADS", text), "must be at least 1 (numba refuses 0)")
    cores = usable_cores()
    if value > cores:  # numba starts them all at its first parallel loop: 1000 under a memory limit abort in libgomp
        raise InputError(named_value("NUMBA_NUM_THREADS", text), f"more threads than the {cores} cores this process may "
                         f"use (at most {cores}; more only slows LBP down)")
    return value


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity; else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def quiet_openmp_threads() -> None:
    """``OMP_WAIT_POLICY=PASSIVE`` unless set: read by OpenMP when numba first starts its threads."""
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


def numba_cache_dir() -> Path | None:
    """``$NUMBA_CACHE_DIR`` if set, checked writable (numba's own error comes only at the first kernel)."""
    text = os.environ.get("NUMBA_CACHE_DIR", "")
    if not text:
        return None  # numba treats an empty value as unset too
    return writable_folder(Path(text).expanduser(), "NUMBA_CACHE_DIR")


def number(variable, what) -> int | None:
    """``$variable`` as a whole number >= 1, or None when it is unset or empty."""
    text = os.environ.get(variable, "")
    return whole_number(variable, text, what) if text.strip() else None


def check(numba_cache_too=True) -> None:
    """Check every variable an entry point depends on, as where each is read (InputError naming the first bad one);
    ``numba_cache_too`` False: all but ``NUMBA_CACHE_DIR`` (``--help`` compiles nothing).

    >>> check()
    """
    numba_threads()
    if numba_cache_too:
        numba_cache_dir()
    number("CRFMAP_MAX_CELLS", "cells")
    folder("CRFMAP_ROOT", must_exist=True)
    folder("CRFMAP_DATA")


def prepare(numba_cache_too=True) -> None:
    """Ready this process for crfmap's kernels (the entry points call it first; a library user may): :func:`check`
    the variables before numba reads ``NUMBA_NUM_THREADS`` once at its import (then failing with a traceback on ``0``,
    or ignoring ``abc``), so the error is crfmap's one line; set ``OMP_WAIT_POLICY``; and :func:`prepare_cache` unless
    ``numba_cache_too`` is False (the ``crfmap`` command calls it after parsing, so ``--help`` needs no writable cache).
    """
    check(numba_cache_too=False)
    quiet_openmp_threads()
    if numba_cache_too:
        prepare_cache()


def prepare_cache() -> None:
    """Check ``NUMBA_CACHE_DIR`` (set: writable) or choose one (:func:`crfmap._numba_cache.configure`)."""
    numba_cache_dir()
    from crfmap._numba_cache import configure

    configure()
