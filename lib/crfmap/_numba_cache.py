"""Where numba keeps crfmap's compiled kernels when the package folder is read-only.

Numba caches ``@njit(cache=True)`` kernels next to the source (``__pycache__``), else in ``~/.cache/numba``; where
neither is writable (a system-wide or container install, a read-only home) it raises "cannot cache function ...: no
locator available" at the first call. :func:`configure` (called by :func:`crfmap.environment.prepare`) then points an
unset ``NUMBA_CACHE_DIR`` at the first writable folder of :func:`fallback_dirs`; a set one is never changed.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def _writable(folder: Path) -> bool:
    """Whether numba could write its cache files into ``folder`` (created if missing)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
        return True
    except OSError:
        return False


def fallback_dirs() -> list[Path]:
    """The user cache folders tried, in order."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    return [Path(base) / "crfmap" / "numba", Path(tempfile.gettempdir()) / f"crfmap-numba-{uid}"]


def choose_cache_dir(package=PACKAGE):
    """The folder to set as NUMBA_CACHE_DIR, or None where numba's own choice works (or one is set)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    folders = [package] + sorted(p for p in package.iterdir() if (p / "__init__.py").is_file())
    if all(_writable(folder / "__pycache__") for folder in folders):
        return None
    for folder in fallback_dirs():
        if _writable(folder):
            return folder
    return None  # nowhere to write: numba's own error will say so


def configure():
    """Set NUMBA_CACHE_DIR if needed (also in an already imported numba)."""
    folder = choose_cache_dir()
    if folder is None:
        return None
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    numba = sys.modules.get("numba")  # imported already: it read the variable then; tell its public config too
    if numba is not None and hasattr(numba, "config"):
        numba.config.CACHE_DIR = str(folder)
    return folder
