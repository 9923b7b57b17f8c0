"""A read-only install: numba's cache=True must not crash where the package folder cannot be written.

As root, chmod does not stop a write, so the install is made unwritable the way numba
notices it: every ``__pycache__`` of a copy of the package is a plain file (no folder can
be made there) and ``$HOME`` is under /proc (numba's user-wide ``~/.cache`` cannot be made
either). Without crfmap's fallback, numba then raises "no locator available"; with it, the
kernels are cached under the temporary folder. The fallback is :func:`crfmap.prepare`'s (the entry points call
it; importing crfmap changes nothing, tests/test_import.py).
"""
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import crfmap

CALL = ("import os, numpy, crfmap; crfmap.prepare(); import crfmap.raycast as r; "
        "print(r.bresenham_step(0, 0, 3, 4, numpy.empty((5, 2), numpy.int64))); print(os.environ.get('NUMBA_CACHE_DIR', '-'))")


def _read_only_install(tmp_path, with_fallback=True):
    site = tmp_path / "site"
    shutil.copytree(Path(crfmap.__file__).parent, site / "crfmap", ignore=shutil.ignore_patterns("__pycache__"))
    if not with_fallback:
        (site / "crfmap" / "_numba_cache.py").write_text("def configure():\n    return None\n")
    for folder in [site / "crfmap", *[p for p in (site / "crfmap").rglob("*") if p.is_dir()]]:
        (folder / "__pycache__").write_text("not a folder")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_CACHE_DIR", "XDG_CACHE_HOME"))}
    (tmp_path / "tmp").mkdir()
    # -S: no .pth files, so a venv's own NUMBA_CACHE_DIR default (make venv writes one) does not hide the case
    packages = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    env.update(PYTHONPATH=os.pathsep.join([str(site), *sorted(packages)]), HOME="/proc/no-such-home", TMPDIR=str(tmp_path / "tmp"),
               PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, "-S", "-c", CALL], env=env, cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)


def test_read_only_install_falls_back_to_a_user_cache(tmp_path):
    run = _read_only_install(tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    out = run.stdout.split()
    assert out[0] == "5"
    cache = Path(out[1])
    assert cache.parent == tmp_path / "tmp" and cache.name.startswith("crfmap-numba-")
    assert any(p.suffix == ".nbi" for p in cache.rglob("*"))  # numba wrote its index there


def test_without_the_fallback_numba_fails_there(tmp_path):
    run = _read_only_install(tmp_path, with_fallback=False)  # shows the simulation is faithful
    assert run.returncode != 0 and "no locator available" in run.stderr


def test_a_set_numba_cache_dir_is_kept(monkeypatch, tmp_path):
    from crfmap import _numba_cache

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert _numba_cache.choose_cache_dir() is None
