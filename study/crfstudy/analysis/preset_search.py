"""The search that chooses the certainty preset's constants: a coordinate search on one recording.

The certainty preset (:mod:`crfmap.crf.presets`) has seven constants: the hidden coupling J, the
log-odds of the first net hit and of each further one ``(a, b)``, the same for net passes
``(c, d)``, the cap ``limit`` on one cell's |log-odds| and the LBP ``margin``. They are chosen by
the scan-split Brier score (all cells the second half observed; :mod:`crfmap.assess.scansplit`)
of the *training* recording only (Intel):

1. start from :data:`START` (each constant on its grid, :data:`GRID`);
2. for each constant in turn (:data:`ORDER`) score every value of its grid with the others fixed,
   and keep the best (strictly lower only: a tie keeps the current value);
3. repeat whole rounds until a round changes nothing (or ``max_rounds``).

Every configuration is scored once (a cache): :attr:`SearchResult.trace` lists them in the order
they were first scored, :attr:`SearchResult.configurations` counts them. The rule is
:mod:`crfstudy.analysis.coordinate`'s, the one the peers' search (:mod:`crfstudy.analysis.peer_search`)
uses too.

The full search on Intel (5 cm cells, even / odd scans) scores about 60 configurations, a minute or
two of LBP: more than a notebook of ``make reproduce`` should spend. Its result is kept in
:data:`CACHE` (``python -m crfstudy.analysis.preset_search`` reruns it and rewrites the file; ``--check``
reruns it and compares), and notebook 10 re-scores the cached best and the preset's own constants.

>>> from crfmap.assess.scansplit import ScanSplit
>>> rng = np.random.default_rng(0)
>>> sp = ScanSplit(*(rng.integers(0, 3, (12, 12)) for _ in range(4)))
>>> r = coordinate_search(sp, grid={"coupling": (0.0, 0.3), "limit": (2.0, 4.0)},
...                       start=dict(START, coupling=0.0, limit=2.0))
>>> r.configurations, sorted(r.best) == sorted(START)
(3, True)
"""
from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from crfmap.errors import InputError
from crfstudy.analysis.coordinate import SearchResult, coordinate_descent  # noqa: F401 - SearchResult: re-exported
from crfmap.crf.presets import coupling_table, get_preset
from crfmap.assess.scansplit import scan_split
from crfmap.io.recordings import load_recording
from crfmap.data import data_file
from crfstudy.analysis.coordinate import check_or_write, split_brier

# the grid each constant is searched on (a, c: first net hit / pass; b, d: each further one)
GRID = {
    "coupling": (0.2, 0.25, 0.3, 0.35, 0.4),  # Ising J, all below J_c = 0.44
    "occupied_first": (0.5, 1.0, 1.5, 2.0, 2.5),
    "occupied_further": (0.1, 0.2, 0.3, 0.5),
    "free_first": (0.25, 0.5, 0.75, 1.0, 1.5),
    "free_further": (0.1, 0.2, 0.3, 0.5),
    "limit": (3.0, 4.0, 5.0, 6.0),
    "margin": (2, 3, 5, 8),
}
CACHE = Path(__file__).with_name("preset_search_intel.json")  # the full search's result on Intel
TRAINING = "carmen/intel-corrected.log.gz"  # the recording the search runs on (crfmap.data.data_file)
TRAINING_RESOLUTION = 0.05  # [m] its cells, as notebook 10
ORDER = tuple(GRID)  # the coordinates in the order one round visits them
START = {"coupling": 0.3, "occupied_first": 1.0, "occupied_further": 0.2, "free_first": 1.0, "free_further": 0.2,
         "limit": 4.0, "margin": 3}

CERTAINTY = "certainty"  # the model searched here (the gated default is this model plus its evidence gate)


def preset_constants(preset) -> dict:
    """The seven searched constants of a :class:`~crfmap.crf.presets.Preset`, named as in :data:`GRID`.

    >>> from crfmap.crf.presets import get_preset
    >>> preset_constants(get_preset(CERTAINTY))["margin"]
    5
    """
    return {"coupling": round(preset.coupling, 9), "occupied_first": preset.occupied[0],
            "occupied_further": preset.occupied[1], "free_first": preset.free[0], "free_further": preset.free[1],
            "limit": preset.limit, "margin": preset.margin}


def preset_from(constants: dict, base: str | None = None):
    """The ``base`` preset (None: the certainty preset, the model this study is about) with the constants of ``constants`` (names of :data:`GRID`)."""
    unknown = set(constants) - set(GRID)
    if unknown:
        raise InputError("constants", f"unknown names {sorted(unknown)}; expected some of {', '.join(GRID)}")
    p = get_preset(CERTAINTY) if base is None else get_preset(base)
    c = {**preset_constants(p), **constants}
    return replace(p, hidden=coupling_table(c["coupling"]),
                   occupied=(float(c["occupied_first"]), float(c["occupied_further"])),
                   free=(float(c["free_first"]), float(c["free_further"])), limit=float(c["limit"]),
                   margin=int(c["margin"]))


def search_brier(split, constants: dict, dtype=np.float32, max_iter: int = 5000) -> float:
    """Scan-split Brier score (all cells) of the preset with ``constants`` on ``split``."""
    beliefs = preset_from(constants).refine(hits=split.first_hits, passes=split.first_passes, dtype=dtype,
                                            max_iter=max_iter).beliefs.probability
    return split_brier(split, beliefs)


def coordinate_search(split, grid: dict | None = None, start: dict | None = None, max_rounds: int = 10,
                      progress: bool = False, **options) -> SearchResult:
    """Coordinate search of the certainty preset's constants by the scan-split Brier score of ``split``.

    ``grid``: {constant: values} (default :data:`GRID`; constants it leaves out stay at ``start``'s
    or the preset's value); ``start``: the first configuration (default :data:`START`), each of its
    searched values on its grid; ``options`` go to :func:`search_brier`. The rule is
    :func:`crfstudy.analysis.coordinate.coordinate_descent`'s, visiting the constants in :data:`ORDER`.
    """
    grid = {k: tuple(v) for k, v in (GRID if grid is None else grid).items()}
    for name in grid:
        if name not in GRID:
            raise InputError("grid", f"unknown constant {name!r}; expected some of {', '.join(GRID)}")
    return coordinate_descent(lambda config: search_brier(split, config, **options), grid,
                              START if start is None else start, order=ORDER, max_rounds=max_rounds,
                              progress=progress, desc="preset search")


def load_cached(path: Path | None = None) -> dict:
    """The cached full search on Intel (:meth:`SearchResult.as_dict` plus ``recording``, ``resolution_m``)."""
    target = CACHE if path is None else Path(path)
    try:
        return json.loads(target.read_text())
    except (OSError, ValueError) as e:
        raise InputError(target, f"cannot read the cached preset search ({e})") from None


def run_training_search(progress: bool = True) -> dict:
    """The full search on the training recording (Intel, even / odd scans at 5 cm), as the cache holds it."""
    recording = load_recording(data_file(TRAINING))
    split = scan_split(recording.scans, TRAINING_RESOLUTION)
    result = coordinate_search(split, progress=progress).as_dict()
    return {**result, "recording": TRAINING, "resolution_m": TRAINING_RESOLUTION, "split": "even/odd scans"}


def main(argv=None) -> int:
    """``python -m crfstudy.analysis.preset_search [--check]``: rerun the search on Intel and (re)write or check the cache."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv not in ([], ["--check"]):
        print("usage: python -m crfstudy.analysis.preset_search [--check]", file=sys.stderr)
        return 2
    try:
        result = run_training_search()
    except InputError as e:  # the data missing included
        print(f"crfmap preset search: {e}", file=sys.stderr)
        return 2
    return check_or_write(result, CACHE, load_cached() if argv == ["--check"] else None, "search")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
