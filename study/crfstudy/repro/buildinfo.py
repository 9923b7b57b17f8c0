"""What the report's reproducibility section states, read at build time from the machine that built it.

:func:`describe` returns the environment actually used (Python, every declared dependency's installed
version), the hardware (CPU model, cores, memory), the public data's files with their sha256, the seeds
of every notebook's ``parameters`` cell and the last full run's wall clock (``out/logs/reproduce_wall.json``).
The paper's ``{{build:KEY}}`` placeholders (:mod:`crfstudy.repro.paper`) are filled from it, so none of
these is typed into the prose.

>>> sorted(describe(data=False))[:4]
['cores', 'cpu', 'crfmap_commit', 'data_table']
"""
from __future__ import annotations

import ast
import hashlib
import json
import os
import platform
import re
import subprocess
import time
from importlib import metadata
from pathlib import Path

from crfmap.data import data_root
from crfstudy import paths
from crfstudy.repro.report import markdown_table
from crfstudy.repro.timings import slowest_cells_table
from crfstudy.repro.variables import reproduce_started

# The data files the notebooks read (folders: every file inside), where each came from.
DATA_ORIGINS = {
    "carmen/intel-corrected.log.gz": "https://github.com/acschaefer/ple (data/carmen/; Radish)",
    "carmen/aces-corrected.log.gz": "https://github.com/acschaefer/ple (data/carmen/; Radish)",
    "carmen/csail-corrected.log.gz": "https://github.com/acschaefer/ple (data/carmen/; Radish)",
    "carmen/freiburg-101-corrected.log.gz": "https://github.com/acschaefer/ple (data/carmen/; Radish)",
    "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2": "https://github.com/comprobo24/robot_localization (bags/)",
    "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml": "https://github.com/comprobo24/robot_localization (bags/)",
    "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.pgm": "https://github.com/comprobo24/robot_localization (bags/)",
    "rosbags/zaki0929_bagfiles/2019_jan17_expt04_bagfile.bag": "https://github.com/zaki0929/bagfiles",
    "images/ugm_X_32x32.csv": "UGM toolbox (M. Schmidt), X.mat, https://www.cs.ubc.ca/~schmidtm/Software/UGM.html",
}
_REQUIREMENT_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)")


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def data_files(root: Path | None = None) -> list:
    """(path under the data folder, size in kB, sha256 or "missing", origin) for every data file."""
    root = Path(root or data_root())
    rows = []
    for relative, origin in DATA_ORIGINS.items():
        target = root / relative
        files = sorted(p for p in target.rglob("*") if p.is_file()) if target.is_dir() else [target]
        for f in files:
            name = f.relative_to(root).as_posix()
            if f.is_file():
                size = f.stat().st_size  # a file under 1 kB keeps its bytes (a 137-byte map YAML read "0 kB")
                rows.append([name, round(size / 1e3) if size >= 1e3 else size / 1e3, _sha256(f), origin])
            else:
                rows.append([name, None, "missing", origin])
    return rows


def package_versions() -> list:
    """(package, installed version) for crfmap's declared dependencies and the test extras, sorted."""
    names = {"crfmap"}
    for requirement in metadata.requires("crfmap") or []:
        match = _REQUIREMENT_NAME.match(requirement)
        if match:
            names.add(match.group(1))
    rows = []
    for name in sorted(names, key=str.lower):
        try:
            rows.append([name, metadata.version(name)])
        except metadata.PackageNotFoundError:
            rows.append([name, "not installed"])
    return rows


def notebook_seeds(notebooks: Path | None = None) -> list:
    """(notebook, seed parameters as "name = value") from each notebook's ``parameters`` cell."""
    rows = []
    for nb in sorted(Path(notebooks or paths.PROJECT_ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")):
        cells = json.loads(nb.read_text()).get("cells", [])
        source = next(("".join(c.get("source", "")) for c in cells
                       if "parameters" in c.get("metadata", {}).get("tags", [])), "")
        seeds = []
        for node in ast.parse(source).body if source else []:
            if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name) and "seed" in node.targets[0].id:
                seeds.append(f"{node.targets[0].id} = {ast.unparse(node.value)}")
        rows.append([nb.stem, "; ".join(seeds) or "none (deterministic)"])
    return rows


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory_gb():
    try:
        return round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    except (ValueError, OSError, AttributeError):
        return None


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=paths.PROJECT_ROOT, text=True,
                              capture_output=True, check=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def wall_record(path: Path | None = None) -> dict:
    """The last full `make reproduce`'s record, or {} when none was written (or it is not a JSON object)."""
    try:
        record = json.loads(Path(path or paths.OUT / "logs" / "reproduce_wall.json").read_text())
    except (OSError, ValueError):
        return {}
    return record if isinstance(record, dict) else {}


def describe(data: bool = True) -> dict:
    """Everything the reproducibility section quotes (``data=False`` skips hashing the data files)."""
    wall = wall_record()
    return {
        "python": platform.python_version(),
        "platform": platform.platform(terse=True),
        "cpu": _cpu_model(),
        "cores": os.cpu_count(),
        "memory_gb": _memory_gb(),
        "crfmap_commit": _commit(),
        "versions": ", ".join(f"{name} {version}" for name, version in package_versions()),
        "data_table": markdown_table(["file", "kB", "sha256 (in groups of 16)"],
                                     [[name, kb, _grouped(digest)] for name, kb, digest, _ in data_files()]
                                     ).rstrip("\n") if data else "",
        "seeds": "; ".join(f"{notebook}: {seeds}" for notebook, seeds in notebook_seeds()),
        "wall": wall_sentence(wall, started=reproduce_started()),
        "slowest_cells": slowest_cells_table(paths.OUT / "notebooks").rstrip("\n"),
    }


def _grouped(digest: str, size: int = 16) -> str:
    """A long hex digest in space-separated groups, so a narrow table column can wrap it.

    >>> _grouped("0123456789abcdef0123")
    '0123456789abcdef 0123'
    """
    return " ".join(digest[i:i + size] for i in range(0, len(digest), size))


def wall_sentence(wall: dict, started: float | None = None) -> str:
    """The last full run's wall clock as a clause of the report, or that none was recorded; with ``started``
    (when the ``make reproduce`` building this report began, Unix time) first how long this run has taken.

    >>> wall_sentence({}, started=time.time() - 90).startswith("this report was built 1.5 minutes after")
    True

    >>> wall_sentence({"workflow_seconds": 600.0, "make_seconds": 660.0, "cores": 2, "finished": "2026-01-01 10:00:00 UTC"})
    'the last full run recorded here (finished 2026-01-01 10:00:00 UTC, 2 cores) took 11.0 minutes from `make reproduce` to the last output (the workflow alone 10.0 minutes)'
    >>> wall_sentence({})
    'no full run was recorded here before this build (out/logs/reproduce_wall.json is written when one ends)'
    """
    if started is not None:  # this run, up to the paper's build (its full record is written when it ends)
        this = (f"this report was built {(time.time() - started) / 60:.1f} minutes after `make reproduce` started "
                "(venv, warm-up and every notebook)")
        return this + "; " + wall_sentence(wall) if wall.get("workflow_seconds") else this
    if not wall.get("workflow_seconds"):
        return "no full run was recorded here before this build (out/logs/reproduce_wall.json is written when one ends)"
    total = wall.get("make_seconds")
    head = f"the last full run recorded here (finished {wall.get('finished')}, {wall.get('cores')} cores) took "
    workflow = f"{wall['workflow_seconds'] / 60:.1f} minutes"
    if total:
        return head + f"{total / 60:.1f} minutes from `make reproduce` to the last output (the workflow alone {workflow})"
    return head + workflow + " (the workflow alone)"
