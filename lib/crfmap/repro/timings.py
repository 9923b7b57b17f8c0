"""How long each notebook takes to run: the workflow's order (longest first) and a sweep's estimate.

The last full run's seconds (``paper/generated/reproduce_timings.json`` under the output root) where
there is one, else :data:`EXPECTED_SECONDS`; a notebook in neither counts as long.
"""
from __future__ import annotations

import json
from pathlib import Path

# a full run on 2 cores, 2026-12-03 06:56 [s]; 09 and 10 scaled by their measured speed-ups since (issue 22)
EXPECTED_SECONDS = {"01_background": 48, "02_worked_example": 19, "03_simulator": 30, "04_denoising": 50,
                    "05_occlusion": 29, "06_enclosed": 36, "07_office": 105, "08_explorer": 9, "09_speed": 48,
                    "10_beyond": 200}
BENCHMARKS = {"09_speed"}  # notebooks that measure speed: each runs alone with every core (its numbers are timings)
UNKNOWN_SECONDS = 1000  # a new notebook: assume it is long, so it starts early
RECORD = Path("paper") / "generated" / "reproduce_timings.json"


def expected_seconds(stems, root=".") -> dict:
    """``{notebook stem: seconds}`` for ``stems``, from ``root``'s last full run where it has one.

    >>> expected_seconds(["04_denoising", "99_new"], root="/nonexistent")
    {'04_denoising': 50, '99_new': 1000}
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
