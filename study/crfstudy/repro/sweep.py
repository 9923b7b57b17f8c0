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

A sweep file is read as strictly as a map YAML (no aliases, bounded nesting and size; a FIFO or device
is refused before it is opened). Every value must have the type of the notebook's parameter (an int is
accepted for a float). A sweep has at most :data:`MAX_POINTS` points unless raised (``--max-points``).
A point's folder name is ``name=label`` per parameter, joined by ``__``; a label is the value's JSON text
with every character but letters, digits and ``. + - [ ] ,`` percent-encoded (a string that would read
as JSON is quoted first), so :func:`parse_point` turns a folder name back into its parameters, and two
points never share a folder -- also not on a case-insensitive file system: a sweep where they would is
refused, naming both.
"""
from __future__ import annotations

import csv
import io
import itertools
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote_to_bytes

from crfstudy import paths
from crfmap.checks import check_int
from crfmap.errors import InputError
from crfmap.io import read_yaml  # the map loader's strict YAML (aliases refused)
from crfmap.io.atomic import atomic_path
from crfstudy.repro.dependencies import declared_outputs, notebooks, parameter_defaults

SEPARATOR = "__"  # between a point's parameters in its folder name: noise=0.3__seed=1
MAX_POINTS = 200  # a sweep's points unless raised (--max-points): each is a full notebook run of ~5-60 s
MAX_SWEEP_BYTES = 256 << 10  # a sweep file is a few lines; 256 KiB holds 200 points of long labels
NAME_MAX = 255  # [bytes] longest file or folder name (Linux, macOS, Windows)
LOG_SUFFIX = ".ipynb"  # a point's log is out/logs/runs/<sweep>/<point>.ipynb: its name is the longest
KEYS = ("notebook", "parameters", "fixed", "headline")
_SAFE = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789.+-[],")
_SWEEP_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]*\Z")  # a file stem usable as folder and snakemake wildcard


@dataclass
class Sweep:
    """A parsed sweep file."""

    name: str
    notebook: Path
    grid: dict
    fixed: dict = field(default_factory=dict)
    headline: list = field(default_factory=list)
    source: Path | None = None  # the sweep file (named by errors)

    def points(self) -> dict:
        """``{point folder name: parameters}`` for every combination of the grid (in grid order).

        Two points with one folder (also when the names differ only in case) raise InputError naming both.

        >>> Sweep("s", Path("04.ipynb"), {"noise": [0.3, 0.5]}, {"quick": True}).points()
        {'noise=0.3': {'quick': True, 'noise': 0.3}, 'noise=0.5': {'quick': True, 'noise': 0.5}}
        >>> list(Sweep("s", Path("08.ipynb"), {"scene": ["a/b", "a-b", "0.3"], "radius": [None]}).points())
        ['scene=a%2Fb__radius=null', 'scene=a-b__radius=null', 'scene=%220.3%22__radius=null']
        """
        names = list(self.grid)
        found, folded = {}, {}
        for values in itertools.product(*(self.grid[n] for n in names)):
            parameters = dict(zip(names, values))
            point = SEPARATOR.join(f"{n}={label(v)}" for n, v in parameters.items())
            other = folded.setdefault(point.casefold(), parameters)
            if other is not parameters:
                raise InputError(self.source or self.name, f"two points would write to one folder, "
                                 f"out/runs/{self.name}/{point}: {_show(other)} and {_show(parameters)} (values "
                                 "must differ after conversion, and in more than letter case)")
            found[point] = {**self.fixed, **parameters}
        return found


def _show(parameters) -> str:
    return "{" + ", ".join(f"{n}: {json.dumps(v)}" for n, v in parameters.items()) + "}"


def label(value) -> str:
    """A value's text in a folder name; :func:`parse_label` reads it back (``label(x)`` differs for every JSON value).

    >>> label(0.3), label("0.3"), label("a/b"), label("a_b"), label([1, 2]), label(None)
    ('0.3', '%220.3%22', 'a%2Fb', 'a%5Fb', '[1,2]', 'null')
    """
    text = json.dumps(value, separators=(",", ":"), allow_nan=False)
    if isinstance(value, str) and not _reads_as_json(value):
        text = value  # a plain word stays plain: "checkerboard", not "%22checkerboard%22"
    return "".join(c if c in _SAFE else "".join(f"%{b:02X}" for b in c.encode()) for c in text)


def _reads_as_json(text) -> bool:
    try:
        json.loads(text)
        return True
    except ValueError:
        return False


def parse_label(text):
    """The value :func:`label` turned into ``text``.

    >>> parse_label("%220.3%22"), parse_label("0.3"), parse_label("a%2Fb")
    ('0.3', 0.3, 'a/b')
    """
    decoded = unquote_to_bytes(text).decode("utf-8")
    try:
        return json.loads(decoded)
    except ValueError:
        return decoded


def parse_point(folder_name) -> dict:
    """A point's parameters from its folder name (labels hold no ``_`` or ``=``: the split is unique).

    >>> parse_point("noise=0.3__scene=a%5Fb__radius=null")
    {'noise': 0.3, 'scene': 'a_b', 'radius': None}
    """
    pieces = folder_name.split("=")
    names, labels = [pieces[0]], []
    for piece in pieces[1:-1]:
        text, name = piece.split(SEPARATOR, 1)
        labels.append(text)
        names.append(name)
    labels.append(pieces[-1])
    return {n: parse_label(t) for n, t in zip(names, labels)}


def load(path, max_points=None) -> Sweep:
    """Read and check a sweep file (errors name the file and what is wrong).

    ``max_points``: refuse more points than this (default :data:`MAX_POINTS`).
    """
    path = Path(path)
    spec = read_yaml(path, "a sweep file (YAML)", limit=MAX_SWEEP_BYTES)
    if not isinstance(spec, dict) or "notebook" not in spec or "parameters" not in spec:
        raise InputError(path, "a sweep needs 'notebook' and 'parameters' (a grid: name -> list of values)")
    unknown = [k for k in spec if k not in KEYS]
    if unknown:
        raise InputError(path, f"unknown key {unknown[0]!r} (a sweep has {', '.join(KEYS)})")
    if not _SWEEP_NAME.match(path.stem):
        raise InputError(path, f"the sweep's name {path.stem!r} (the file's stem, its output folder) must be "
                         "letters, digits and . _ + - (starting with a letter or digit)")
    if not isinstance(spec["notebook"], str) or not spec["notebook"]:
        raise InputError(path, f"'notebook' must name a notebook of {paths.NOTEBOOKS}, got {spec['notebook']!r}")
    matches = notebooks([spec["notebook"]])
    if len(matches) != 1:
        raise InputError(path, f"notebook {spec['notebook']!r} matches {len(matches)} notebooks in {paths.NOTEBOOKS}")
    grid, fixed = spec["parameters"], spec.get("fixed") or {}
    if not isinstance(grid, dict) or not grid or not all(isinstance(v, list) and v for v in grid.values()):
        raise InputError(path, "'parameters' must map each parameter to a non-empty list of values")
    if not isinstance(fixed, dict):
        raise InputError(path, f"'fixed' must map parameters to values, got {type(fixed).__name__}")
    known = parameter_defaults(matches[0])
    unknown = sorted(n if isinstance(n, str) and n.isidentifier() else repr(n)
                     for n in (set(grid) | set(fixed)) - set(known))
    if unknown:
        raise InputError(path, f"{', '.join(unknown)} not in the parameters cell of {matches[0].name} "
                         f"(it has {', '.join(known)})")
    both = [n for n in grid if n in fixed]
    if both:
        raise InputError(path, f"{both[0]} is both swept ('parameters') and fixed ('fixed')")
    headline = spec.get("headline") or []
    if not isinstance(headline, list) or not all(isinstance(h, str) for h in headline):
        raise InputError(path, "'headline' must be a list of number names, e.g. [denoising.mse_after]")
    _check_count(path, grid, MAX_POINTS if max_points is None else check_int("max_points", max_points, low=1))
    where = f"{matches[0].name}'s parameters cell"
    grid = {n: [_typed(path, n, v, known[n], where) for v in values] for n, values in grid.items()}
    fixed = {n: _typed(path, n, v, known[n], where) for n, v in fixed.items()}
    sweep = Sweep(path.stem, matches[0], grid, fixed, headline, path)
    _check_name_lengths(path, sweep)
    sweep.points()  # two points with one folder: refused here, naming both
    return sweep


def _check_count(path, grid, limit) -> int:
    count = math.prod(len(v) for v in grid.values())
    if count > limit:
        shape = " x ".join(str(len(v)) for v in grid.values())
        raise InputError(path, f"{count:,} points ({shape}) exceed the limit of {limit:,} (each point is a notebook "
                         "run; raise the limit with --max-points N)")
    return count


def _check_name_lengths(path, sweep) -> None:
    """Every point's folder name (and its log's file name) fits in :data:`NAME_MAX` bytes."""
    longest = {n: max(values, key=lambda v: len(label(v).encode())) for n, values in sweep.grid.items()}
    point = SEPARATOR.join(f"{n}={label(v)}" for n, v in longest.items())
    size = len((point + LOG_SUFFIX).encode())
    if size > NAME_MAX:
        name = max(longest, key=lambda n: len(label(longest[n])))
        raise InputError(path, f"the point folder name for {name} = {json.dumps(longest[name])[:60]}... would be "
                         f"{size} bytes with its log's {LOG_SUFFIX} (at most {NAME_MAX}): use shorter values")


def _typed(path, name, value, default, where):
    """``value`` for parameter ``name`` if it has the type of the notebook's ``default`` (an int for a float)."""
    _check_scalars(path, name, value)
    if default is None:  # the notebook takes None or something else: any scalar or flat list
        return value
    if isinstance(default, float) and type(value) is int:  # noise: [1] means 1.0 (bools are not ints here)
        if abs(value) > 1e300:  # float() would overflow; no notebook parameter is near
            raise InputError(path, f"{name}: {str(value)[:40]}... is too large a number")
        return float(value)
    if type(value) is not type(default):
        raise InputError(path, f"{name}: {json.dumps(value)[:80]} is {_kind(value)}, but {name} = "
                         f"{json.dumps(default)[:40]} in {where} is {_kind(default)}")
    if isinstance(default, list) and default and len({type(d) for d in default}) == 1:
        return [_typed(path, name, v, default[0], where) for v in value]
    return value


def _kind(value) -> str:
    kinds = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list",
             dict: "a mapping", type(None): "none (null)"}
    return kinds.get(type(value), type(value).__name__)


def _check_scalars(path, name, value, depth=0) -> None:
    """Values are YAML scalars or flat lists of them: finite numbers, strings without control characters."""
    if isinstance(value, list) and depth == 0:
        for item in value:
            _check_scalars(path, name, item, 1)
        return
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(path, f"{name}: {value} is not a finite number")
    if isinstance(value, str):
        bad = next((c for c in value if ord(c) < 32 or ord(c) == 127), None)
        if bad is not None:
            what = "a NUL byte" if bad == "\0" else f"a control character (U+{ord(bad):04X})"
            raise InputError(path, f"{name}: the value {json.dumps(value)[:60]} holds {what}")
        return
    if not isinstance(value, (bool, int, float, type(None))):
        raise InputError(path, f"{name}: {_kind(value)} is not a value a notebook parameter takes "
                         "(numbers, strings, true/false, null, or a flat list of them)")


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
