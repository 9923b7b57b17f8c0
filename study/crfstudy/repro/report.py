"""Saving what notebooks produce: figures to ``figures/``, tables and numbers to ``paper/generated/``.

Every notebook saves through these functions (and so through :mod:`crfstudy.paths`), atomically,
so the paper always quotes the numbers the code produced. Every saved file records the run that made
it (notebook, parameters, ``quick``; :mod:`crfstudy.repro.provenance`), so the paper build can refuse
a quick or non-default result.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from crfstudy import paths
from crfmap.io.atomic import atomic_path
from crfstudy.repro import provenance, variables, warmup


def start_notebook() -> None:
    """A notebook's first call: check the environment (:func:`crfstudy.repro.variables.prepare`) and, in a Jupyter
    kernel whose numba cache is cold, compile the kernels now, with a message (:func:`warmup.announce_if_cold`),
    so the pause happens where the message is, not on a silent later cell."""
    variables.prepare()
    warmup.announce_if_cold()


def _clean(value):
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return None if math.isnan(v) or math.isinf(v) else v
    return value


def save_figure(fig, name: str, dpi: int = 150, vector: bool = True) -> Path:
    """Save a matplotlib figure as ``figures/<name>.png``; returns the path.

    ``vector=True`` also writes ``figures/<name>.pdf`` (vector lines and text) for authors who
    include the figures in LaTeX.
    """
    stamp = json.dumps(_clean(provenance.current()), sort_keys=True)  # a bad CRFMAP_RUN: refused before any write
    paths.output_dir(paths.FIGURES)
    target = paths.FIGURES / f"{name}.png"
    with atomic_path(target) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="png", metadata={provenance.PNG_KEY: stamp})
    if vector:
        with atomic_path(target.with_suffix(".pdf")) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="pdf")
    return target


def save_numbers(name: str, numbers: dict) -> Path:
    """Save a dict of numbers as ``paper/generated/<name>.json`` (NaN/inf become null).

    The file also holds the run that made it under ``"_provenance"``.
    """
    data = {**_clean(numbers), provenance.KEY: _clean(provenance.current())}
    paths.output_dir(paths.GENERATED)
    target = paths.GENERATED / f"{name}.json"
    with atomic_path(target) as tmp:
        Path(tmp).write_text(json.dumps(data, indent=2, sort_keys=True) + "\n")
    return target


def load_numbers(name: str) -> dict:
    """The numbers saved by :func:`save_numbers` (without the run record)."""
    data = json.loads((paths.GENERATED / f"{name}.json").read_text())
    data.pop(provenance.KEY, None)
    return data


def format_cell(value, digits: int = 4) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "n/a"
        if v != 0 and (abs(v) < 10 ** -(digits - 1) or abs(v) >= 1e5):
            return f"{v:.{digits - 1}e}"
        return f"{v:.{digits}f}".rstrip("0").rstrip(".") if "." in f"{v:.{digits}f}" else f"{v:.{digits}f}"
    return str(value)


def escape_cell(text: str) -> str:
    """A cell's text safe inside a Markdown table row: a raw "|" would end the cell, a newline the row, and a lone
    backslash is Markdown's escape ("learned on \\ scored on" printed without its backslash).

    >>> escape_cell("P(occ | N = 0.8)"), escape_cell("learned on \\\\ scored on")
    ('P(occ \\\\| N = 0.8)', 'learned on \\\\\\\\ scored on')
    """
    text = re.sub(r"\\(?!\|)", r"\\\\", str(text))  # a backslash not escaping a bar (that one is kept)
    return re.sub(r"(?<!\\)\|", r"\\|", text).replace("\n", " ")


def markdown_table(header, rows, digits: int = 4) -> str:
    """A GitHub-flavoured Markdown table (cells escaped: :func:`escape_cell`)."""
    lines = ["| " + " | ".join(escape_cell(h) for h in header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        lines.append("| " + " | ".join(escape_cell(format_cell(v, digits)) for v in row) + " |")
    return "\n".join(lines) + "\n"


def save_table(name: str, header, rows, digits: int = 4, caption: str = "") -> Path:
    """Save a table as ``paper/generated/<name>.md`` (Markdown) and ``<name>.json`` (raw values)."""
    paths.output_dir(paths.GENERATED)
    text = (f"{caption}\n\n" if caption else "") + markdown_table(header, rows, digits)
    text += provenance.MD_PREFIX + json.dumps(_clean(provenance.current()), sort_keys=True) + " -->\n"
    target = paths.GENERATED / f"{name}.md"
    with atomic_path(target) as tmp:
        Path(tmp).write_text(text)
    save_numbers(name, {"header": list(header), "rows": [list(r) for r in rows], "caption": caption})
    return target


def show_table(table) -> "IPython.display.Markdown":  # noqa: F821
    """A saved table (its name, or the path :func:`save_table` returned) rendered in a notebook.

    Returns an ``IPython.display.Markdown`` object: as a cell's last expression (or passed to
    ``display``) Jupyter renders it as a table with its caption, not as pipe text.
    """
    from IPython.display import Markdown

    target = Path(table) if isinstance(table, Path) else paths.GENERATED / f"{table}.md"
    return Markdown(target.read_text())
