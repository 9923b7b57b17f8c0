"""The search rule every searched row of the study uses: a coordinate search over a grid of values.

One rule for the certainty preset (:mod:`crfstudy.analysis.preset_search`) and the peers
(:mod:`crfstudy.analysis.peer_search`), so a peer is tuned exactly as the preset was:

1. start from ``start`` (each searched constant on its grid);
2. for each constant in turn (``order``) score every value of its grid with the others fixed, and
   keep the best (strictly lower only: a tie keeps the current value);
3. repeat whole rounds until a round changes nothing (or ``max_rounds``).

Every configuration is scored once (a cache): :attr:`SearchResult.trace` lists them in the order
they were first scored, :attr:`SearchResult.configurations` counts them (the search's budget).

>>> r = coordinate_descent(lambda c: (c["x"] - 2) ** 2 + (c["y"] + 1) ** 2,
...                        grid={"x": (0, 1, 2, 3), "y": (-2, -1, 0)}, start={"x": 0, "y": 0})
>>> r.best, r.best_brier, r.configurations, r.rounds
({'x': 2, 'y': -1}, 0.0, 9, 2)
"""
from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path

from crfmap.assess import score
from crfmap.errors import InputError
from crfmap.io.atomic import atomic_path


def split_brier(split, p) -> float:
    """The scan-split Brier score over all cells the second half observed of one [y, x] P grid: every search's
    objective (and the study's single-number score of a grid)."""
    return score(split, {"p": p}, n_boot=0, groups=("all",), metrics=("brier",))["p"]["all"]["brier"]


@dataclass
class SearchResult:
    """What a coordinate search returns: the best constants, the trace and the grid searched."""

    best: dict
    best_brier: float
    trace: list = field(default_factory=list)  # {"round", "coordinate", **constants, "brier"} per new configuration
    rounds: int = 0
    converged: bool = False  # True: the last round changed nothing
    grid: dict = field(default_factory=dict)
    start: dict = field(default_factory=dict)

    @property
    def configurations(self) -> int:
        """How many distinct configurations were scored."""
        return len(self.trace)

    def interior(self) -> dict:
        """{constant: True when its best value has a grid value on either side} (an edge asks for a wider grid).

        >>> SearchResult({"x": 1, "y": 0}, 0.0, grid={"x": (0, 1, 2), "y": (0, 1)}).interior()
        {'x': True, 'y': False}
        """
        return {k: 0 < list(v).index(self.best[k]) < len(v) - 1 for k, v in self.grid.items()}

    def as_dict(self) -> dict:
        return {"best": self.best, "best_brier": self.best_brier, "rounds": self.rounds, "converged": self.converged,
                "configurations": self.configurations, "grid": {k: list(v) for k, v in self.grid.items()},
                "start": self.start, "order": list(self.grid), "trace": self.trace}


def coordinate_descent(score, grid: dict, start: dict, order=None, max_rounds: int = 10, progress: bool = False,
                       desc: str = "search") -> SearchResult:
    """Coordinate search minimising ``score(constants) -> float`` over ``grid`` ({constant: values}).

    ``start``: the first configuration (every searched constant on its grid; it may hold fixed
    constants the grid leaves out); ``order``: the constants in the order a round visits them
    (default: the grid's order; constants not in the grid are skipped).
    """
    from tqdm.auto import tqdm

    grid = {k: tuple(v) for k, v in grid.items()}
    start = dict(start)
    for name, values in grid.items():
        if not values:
            raise InputError("grid", f"{name} has no values to try")
        if start.get(name) not in values:
            raise InputError("start", f"{name} = {start.get(name)!r} is not on its grid {list(values)}")
    if not (isinstance(max_rounds, int) and max_rounds >= 1):
        raise InputError("max_rounds", f"must be a positive integer, got {max_rounds!r}")
    order = [k for k in (grid if order is None else order) if k in grid]
    scores, trace = {}, []
    bar = tqdm(desc=desc, disable=not progress, leave=False)

    def scored(config, round_, coordinate):
        key = tuple(sorted(config.items()))
        if key not in scores:
            scores[key] = float(score(config))
            trace.append({"round": round_, "coordinate": coordinate, **config, "brier": scores[key]})
            bar.update()
        return scores[key]

    current, best = dict(start), scored(start, 0, "start")
    rounds, converged = 0, False
    for rounds in range(1, max_rounds + 1):
        changed = False
        for name in order:
            for value in grid[name]:
                candidate = dict(current, **{name: value})
                b = scored(candidate, rounds, name)
                if b < best:
                    current, best, changed = candidate, b, True
        if not changed:
            converged = True
            break
    bar.close()
    return SearchResult(best=current, best_brier=float(best), trace=trace, rounds=rounds, converged=converged,
                        grid=grid, start=start)


def check_or_write(result: dict, cache, cached: dict | None, label: str, details: str = "") -> int:
    """The end of a search command: with ``cached`` (``--check``), say whether the rerun ``result`` chose what the
    cache holds (exit status 0) or not (1); without, write ``result`` to ``cache`` atomically and say so."""
    if cached is not None:
        same = cached["best"] == result["best"] and len(cached["trace"]) == len(result["trace"])
        print(f"{label} best {result['best']} (Brier {result['best_brier']:.7f}); cache "
              f"{'agrees' if same else 'DIFFERS: ' + str(cached['best'])}")
        return 0 if same else 1
    with atomic_path(cache) as tmp:
        Path(tmp).write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
    print(f"wrote {cache}: best {result['best']} (Brier {result['best_brier']:.7f}), "
          f"{result['configurations']} configurations, {result['rounds']} rounds{details}")
    return 0
