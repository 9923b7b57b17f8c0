"""Every numbered notebook executes headlessly under papermill with its small (quick) settings.

Outputs go to a temporary folder (CRFMAP_OUTPUT_ROOT), never into the checkout.
"""
import json
from pathlib import Path

import pytest

from crfmap.data import data_root, have_data
from crfstudy.repro.dependencies import data_needed

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
MAX_CELL_LINES = 30  # a longer code cell is library code: it goes to crfstudy.experiments (and gets a test)


def long_code_cells(notebook, limit=MAX_CELL_LINES) -> list:
    """(cell index, lines) of every code cell of ``notebook`` longer than ``limit`` lines."""
    cells = json.loads(Path(notebook).read_text())["cells"]
    lengths = [(i, len("".join(c["source"]).splitlines())) for i, c in enumerate(cells) if c["cell_type"] == "code"]
    return [(i, n) for i, n in lengths if n > limit]


def test_code_cells_are_at_most_30_lines():
    too_long = [f"{nb.name} cell {i}: {n} lines" for nb in NOTEBOOKS for i, n in long_code_cells(nb)]
    assert len(NOTEBOOKS) >= 10
    assert not too_long, f"code cells over {MAX_CELL_LINES} lines: " + "; ".join(too_long)


def test_the_cell_length_check_counts_every_line(tmp_path):
    cell = {"cell_type": "code", "source": ["a = 1\n", "\n"] * 15 + ["b = 2"], "metadata": {}, "outputs": []}
    text = {"cell_type": "markdown", "source": ["line\n"] * 40, "metadata": {}}
    path = tmp_path / "nb.ipynb"
    path.write_text(json.dumps({"cells": [text, cell, dict(cell, source=cell["source"][:30])]}))
    assert long_code_cells(path) == [(1, 31)]


@pytest.mark.slow  # 15 s to minutes each; `make test` runs them in parallel (pytest -n)
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(notebook, tmp_path, monkeypatch):
    from crfstudy.repro.run import import_papermill

    pm = import_papermill()

    missing = [f for f in data_needed(notebook) if not have_data(f)]
    if missing:
        pytest.skip(f"{notebook.name} needs shared data not found under {data_root()}: {', '.join(missing)} "
                    "(see data/README.md)")

    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    out = tmp_path / "out" / notebook.name
    out.parent.mkdir(parents=True)
    pm.execute_notebook(str(notebook), str(out), parameters={"quick": True}, kernel_name="python3",
                        cwd=str(notebook.parent), progress_bar=False, execution_timeout=1200)
    produced = list((tmp_path / "figures").glob("*.png")) + list((tmp_path / "paper" / "generated").glob("*"))
    assert produced, f"{notebook.name} saved no figure or table"
