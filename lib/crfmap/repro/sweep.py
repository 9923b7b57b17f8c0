"""Sweeps: a notebook run over a grid of parameters, one output folder per point, one collected table.

A sweep is a YAML file in ``workflow/sweeps/`` (its name is the file's stem)::

    notebook: 04_denoising          # a notebook of notebooks/, by name or prefix
    parameters:                     # the grid: every combination is one point
      noise: [0.3, 0.42, 0.5]
    fixed: {}                       # the same for every point, e.g. {quick: true}
    headline: [denoising.mse_noisy] # optional: which numbers to collect (default: every top-level
                                    # number the notebook saves with save_numbers)

The workflow runs each point into ``out/runs/<sweep>/<point>/`` (its executed notebook, figures/,
paper/generated/) and :func:`collect` writes ``out/runs/<sweep>/collected.csv`` and ``.json`` (one
row per point: its parameters and headline numbers) and ``collected.png``. Points never write into
the checkout's figures/ or paper/generated/, and their results record their parameters, so the paper
build refuses them.
"""
from __future__ import annotations

import csv
import io
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from crfmap import paths
from crfmap.errors import InputError
from crfmap.io.atomic import atomic_path
from crfmap.repro.dependencies import declared_outputs, notebooks, parameter_defaults

SEPARATOR = "__"  # between a point's parameters in its folder name: noise=0.3__seed=1


@dataclass
class Sweep:
    """A parsed sweep file."""

    name: str
    notebook: Path
    grid: dict
    fixed: dict = field(default_factory=dict)
    headline: list = field(default_factory=list)

    def points(self) -> dict:
        """``{point folder name: parameters}`` for every combination of the grid (in grid order).

        >>> Sweep("s", Path("04.ipynb"), {"noise": [0.3, 0.5]}, {"quick": True}).points()
        {'noise=0.3': {'quick': True, 'noise': 0.3}, 'noise=0.5': {'quick': True, 'noise': 0.5}}
        """
        names = list(self.grid)
        found = {}
        for values in itertools.product(*(self.grid[n] for n in names)):
            point = SEPARATOR.join(f"{n}={_label(v)}" for n, v in zip(names, values))
            found[point] = {**self.fixed, **dict(zip(names, values))}
        return found


def _label(value) -> str:
    return json.dumps(value).replace("/", "-").replace(" ", "").strip('"')


def load(path) -> Sweep:
    """Read and check a sweep file (errors name the file and what is wrong)."""
    path = Path(path)
    try:
        spec = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as error:
        raise InputError(path, f"cannot read the sweep ({error})") from None
    if not isinstance(spec, dict) or "notebook" not in spec or "parameters" not in spec:
        raise InputError(path, "a sweep needs 'notebook' and 'parameters' (a grid: name -> list of values)")
    matches = notebooks([str(spec["notebook"])])
    if len(matches) != 1:
        raise InputError(path, f"notebook {spec['notebook']!r} matches {len(matches)} notebooks in {paths.NOTEBOOKS}")
    grid, fixed = spec["parameters"], spec.get("fixed") or {}
    if not isinstance(grid, dict) or not grid or not all(isinstance(v, list) and v for v in grid.values()):
        raise InputError(path, "'parameters' must map each parameter to a non-empty list of values")
    known = parameter_defaults(matches[0])
    unknown = sorted((set(grid) | set(fixed)) - set(known))
    if unknown:
        raise InputError(path, f"{', '.join(unknown)} not in the parameters cell of {matches[0].name} "
                         f"(it has {', '.join(known)})")
    return Sweep(path.stem, matches[0], grid, fixed, list(spec.get("headline") or []))


def sweep_files(folder=None) -> list[Path]:
    """The sweep files of ``workflow/sweeps/`` (or ``folder``)."""
    return sorted(Path(folder or paths.PROJECT_ROOT / "workflow" / "sweeps").glob("*.yaml"))


def _flatten(prefix, value, out):
    if isinstance(value, dict):
        for k, v in value.items():
            if not str(k).startswith("_"):
                _flatten(f"{prefix}.{k}", v, out)
    elif isinstance(value, (int, float)) and not isinstance(value, bool) or value is None:
        out[prefix] = value


def headline_numbers(sweep: Sweep, point_root) -> dict:
    """The headline numbers of one point's run (from the ``save_numbers`` files of the notebook)."""
    numbers = {}
    for relative in declared_outputs(sweep.notebook):
        if not (relative.startswith("paper/generated/") and relative.endswith(".json")):
            continue
        file = Path(point_root) / relative
        if not file.is_file() or Path(relative).with_suffix(".md").name in {
                Path(r).name for r in declared_outputs(sweep.notebook)}:
            continue  # tables are collected from their notebook's numbers, not cell by cell
        data = json.loads(file.read_text())
        for key, value in data.items():
            if not key.startswith("_"):
                _flatten(f"{file.stem}.{key}", value, numbers)
    if sweep.headline:
        missing = [k for k in sweep.headline if k not in numbers]
        if missing:
            raise InputError(point_root, f"headline numbers {', '.join(missing)} not saved by {sweep.notebook.name}")
        numbers = {k: numbers[k] for k in sweep.headline}
    return numbers


def collect(sweep: Sweep, run_root) -> list[dict]:
    """Write ``collected.csv``, ``collected.json`` and ``collected.png`` under ``run_root``; returns the rows."""
    run_root = Path(run_root)
    rows = [{"point": point, **parameters, **headline_numbers(sweep, run_root / point)}
            for point, parameters in sweep.points().items()]
    columns = list(dict.fromkeys(k for row in rows for k in row))
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=columns)
    writer.writeheader()
    writer.writerows(rows)
    with atomic_path(run_root / "collected.csv") as tmp:
        Path(tmp).write_text(text.getvalue())
    with atomic_path(run_root / "collected.json") as tmp:
        Path(tmp).write_text(json.dumps({"sweep": sweep.name, "notebook": sweep.notebook.name, "grid": sweep.grid,
                                         "fixed": sweep.fixed, "rows": rows}, indent=2) + "\n")
    _plot(sweep, rows, run_root / "collected.png")
    return rows


def _plot(sweep: Sweep, rows: list, target: Path, most: int = 6) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x_name = next((n for n, v in sweep.grid.items() if len(v) > 1), next(iter(sweep.grid)))
    others = [n for n in sweep.grid if n != x_name]
    names = [k for k in rows[0] if k not in sweep.grid and k not in sweep.fixed and k != "point"][:most]
    fig, axes = plt.subplots(1, max(len(names), 1), figsize=(3.2 * max(len(names), 1), 3), layout="constrained",
                             squeeze=False)
    for ax, name in zip(axes[0], names):
        groups = {}
        for row in rows:
            groups.setdefault(tuple(row[o] for o in others), []).append(row)
        for key, group in groups.items():
            label = ", ".join(f"{o}={v}" for o, v in zip(others, key)) or None
            ax.plot([r[x_name] for r in group], [r.get(name) for r in group], "o-", label=label)
        ax.set_xlabel(x_name)
        ax.set_title(name, fontsize=8)
        if others:
            ax.legend(fontsize=7)
    fig.suptitle(f"sweep {sweep.name}: {sweep.notebook.name}", fontsize=9)
    with atomic_path(target) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
