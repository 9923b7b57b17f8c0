"""How long each notebook takes to run: the workflow's order (longest first) and a sweep's estimate.

The last full run's seconds (``paper/generated/reproduce_timings.json`` under the output root) where
there is one, else :data:`EXPECTED_SECONDS`; a notebook in neither counts as long.
"""
from __future__ import annotations

import json
from pathlib import Path

from crfstudy.repro.report import markdown_table

# a fresh-clone full run on 2 cores, 2026-12-03 13:31 [s]
EXPECTED_SECONDS = {"01_background": 26, "02_worked_example": 19, "03_simulator": 29, "04_denoising": 44,
                    "05_occlusion": 31, "06_enclosed": 35, "07_office": 75, "08_explorer": 9, "09_speed": 73,
                    "10_beyond": 167}
BENCHMARKS = {"09_speed"}  # notebooks that measure speed: each runs alone with every core (its numbers are timings)
UNKNOWN_SECONDS = 1000  # a new notebook: assume it is long, so it starts early
RECORD = Path("paper") / "generated" / "reproduce_timings.json"


def expected_seconds(stems, root=".") -> dict:
    """``{notebook stem: seconds}`` for ``stems``, from ``root``'s last full run where it has one.

    >>> expected_seconds(["04_denoising", "99_new"], root="/nonexistent")
    {'04_denoising': 44, '99_new': 1000}
    """
    seconds = {stem: EXPECTED_SECONDS.get(stem, UNKNOWN_SECONDS) for stem in stems}
    try:
        last = json.loads((Path(root) / RECORD).read_text())["seconds"]
        last = dict(last)
    except (OSError, ValueError, KeyError, TypeError):
        last = {}
    for name, value in last.items():
        if Path(name).stem in seconds and isinstance(value, (int, float)) and value > 0:
            seconds[Path(name).stem] = value
    return seconds


def describe(seconds) -> str:
    """A duration in words for a person.

    >>> describe(42), describe(5400), describe(200000)
    ('42 s', '1.5 h', '2.3 days')
    """
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 5400 - 1:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def slowest_cells(executed, n=5) -> list:
    """The ``n`` slowest code cells of each executed notebook in folder ``executed``, slowest first.

    Read from the durations papermill stores in each cell's metadata. One row per cell:
    ``(notebook stem, cell index, seconds, its first line of code that is not an import)``; a notebook no run has
    executed yet is absent, a file that is not a notebook is named in a ValueError.
    """
    rows = []
    for path in sorted(Path(executed).glob("*.ipynb")):
        try:
            cells = json.loads(path.read_text())["cells"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"{path}: not an executed notebook ({exc})") from None
        timed = []
        for index, cell in enumerate(cells):
            seconds = (cell.get("metadata", {}).get("papermill") or {}).get("duration")
            if cell.get("cell_type") == "code" and isinstance(seconds, (int, float)):
                timed.append((path.stem, index, float(seconds), _telling_line(cell.get("source", ""))))
        rows += sorted(timed, key=lambda row: -row[2])[:n]
    return rows


def _telling_line(source) -> str:
    r"""The first line of a cell's code that is not an import (imports say little about the cost).

    >>> _telling_line(["import time\n", "from a import b\n", "\n", "run(x)\n"])
    'run(x)'
    """
    lines = [line.strip() for line in "".join(source).splitlines() if line.strip()]
    telling = [line for line in lines if not line.startswith(("import ", "from "))]
    return (telling or lines or [""])[0]


def slowest_cells_table(executed, n=5, width=60) -> str:
    """:func:`slowest_cells` as a markdown table (``notebook | cell | s | code``), or a sentence when none ran.

    >>> slowest_cells_table("/nonexistent")
    'no executed notebooks under /nonexistent'
    """
    rows = slowest_cells(executed, n)
    if not rows:
        return f"no executed notebooks under {executed}"

    def code(text):
        text = text if len(text) <= width else text[:width - 3] + "..."
        return "`" + text.replace("`", "'") + "`"

    return markdown_table(["notebook", "cell", "s", "first line"],
                          [[stem, index, f"{seconds:.1f}", code(first)] for stem, index, seconds, first in rows])
